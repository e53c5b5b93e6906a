#include "ident/mem_fit.hpp"

#include <boost/math/tools/minima.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fmt/format.h>

#include "core/errors.hpp"
#include "ident/fit_checks.hpp"
#include "ident/fit_clock.hpp"
#include "ident/mem_projection.hpp"
#include "ident/mem_refine.hpp"

namespace hystloop {

void MemFitOptions::validate() const {
  require_positive("c3_min", c3_min);
  require_positive("c3_max", c3_max);
  if (!(c3_max > c3_min)) throw ParameterError("c3_max", "must be > c3_min");
  if (c3_grid_points < 3) throw ParameterError("c3_grid_points", "must be >= 3");
  if (brent_bits < 8 || brent_bits > 52) throw ParameterError("brent_bits", "must be in [8, 52]");
  require_non_negative("min_snr", min_snr);
  if (derivative_lag < 1) throw ParameterError("derivative_lag", "must be >= 1");
  require_non_negative("noise_rms_m", noise_rms_m);
  require_non_negative("reversal_dead_band_V", reversal_dead_band_V);
  if (min_branches < 1) throw ParameterError("min_branches", "must be >= 1");
  if (min_samples < 4) throw ParameterError("min_samples", "must be >= 4");
  require_non_negative("min_input_range_V", min_input_range_V);
  require_in_range("min_c1_fraction", min_c1_fraction, 0.0, 1.0);
  require_positive("robust_scale_sigmas", robust_scale_sigmas);
  require_positive("max_solver_time_s", max_solver_time_s);
  if (max_solver_iterations < 1) throw ParameterError("max_solver_iterations", "must be >= 1");
}

double mem_branch_rms(std::span<const double> u_V, std::span<const double> y_m, std::span<const BranchSegment> branches,
                      const MemParams& params) {
  double ss = 0.0;
  std::size_t n = 0;
  for (const BranchSegment& b : branches) {
    double sum = 0.0, sum2 = 0.0;
    for (std::size_t k = b.begin; k < b.end; ++k) {
      const double d = y_m[k] - b.direction * params.branch_rise(std::abs(u_V[k] - b.origin_u));
      sum += d;
      sum2 += d * d;
    }
    const double m = static_cast<double>(b.size());
    ss += sum2 - sum * sum / m;
    n += b.size();
  }
  return n == 0 ? 0.0 : std::sqrt(std::max(ss, 0.0) / static_cast<double>(n));
}

namespace {

using detail::DerivativeData;
using detail::IntegratedData;
using detail::LinearPart;
using detail::ScaledMem;

struct Scales {
  double u = 1.0;       // U [V]: largest p
  double y = 1.0;       // Y [m]: half the output range
  double y_span = 0.0;  // [m] output range on the branches
};

MemFitResult refuse(MemFitResult r, FitStatus status, const std::string& reason) {
  return with_status(std::move(r), status, reason);
}

IntegratedData build_integrated(std::span<const double> u, std::span<const double> y,
                                const std::vector<BranchSegment>& branches, const Scales& sc, const MemFitOptions& o,
                                std::size_t stride = 1) {
  IntegratedData d;
  d.c1_floor_fraction = o.min_c1_fraction;
  std::size_t n = 0;
  for (const auto& b : branches) n += b.size();
  d.p.reserve(n), d.log_p.reserve(n), d.s.reserve(n), d.y.reserve(n);
  d.group_begin.push_back(0);
  for (const auto& b : branches) {
    for (std::size_t k = b.begin; k < b.end; k += stride) {
      const double p = std::abs(u[k] - b.origin_u) / sc.u;
      d.p.push_back(p);
      d.log_p.push_back(p > 0.0 ? std::log(p) : detail::kLogZero);
      d.s.push_back(b.direction);
      d.y.push_back(y[k] / sc.y);
    }
    d.group_begin.push_back(d.p.size());
  }
  d.precompute();
  return d;
}

DerivativeData build_derivative(std::span<const double> u, std::span<const double> y,
                                const std::vector<BranchSegment>& branches, const Scales& sc, double min_du_V,
                                const MemFitOptions& o, std::size_t stride = 1) {
  const auto lag = static_cast<std::size_t>(o.derivative_lag);
  DerivativeData d;
  d.c1_floor_fraction = o.min_c1_fraction;
  std::size_t count = 0;
  for (const auto& b : branches) {
    for (std::size_t k = b.begin + lag; k < b.end; ++k) {
      const double pa = std::abs(u[k - lag] - b.origin_u), pb = std::abs(u[k] - b.origin_u);
      const double dp = pb - pa;
      if (!(dp > 0.0) || dp < min_du_V) continue;  // below the SNR threshold (or a hold)
      if (count++ % stride != 0) continue;
      const double pas = pa / sc.u, pbs = pb / sc.u;
      d.log_pa.push_back(pas > 0.0 ? std::log(pas) : detail::kLogZero);
      d.log_pb.push_back(std::log(pbs));
      d.inv_dp.push_back(1.0 / (pbs - pas));
      d.z.push_back(b.direction * (y[k] - y[k - lag]) / sc.y / (pbs - pas));
    }
  }
  d.precompute();
  return d;
}

// Coarse log grid (on every kGridStride-th sample: it only has to bracket) to find the global
// minimum of the projected residual, then Brent on all samples.
constexpr std::size_t kGridStride = 8;

template <class Data>
double search_c3(const Data& coarse, const Data& data, const MemFitOptions& o) {
  const int g = o.c3_grid_points;
  const double l0 = std::log(o.c3_min), l1 = std::log(o.c3_max);
  std::vector<double> grid(static_cast<std::size_t>(g)), cost(grid.size());
  std::size_t best = 0;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    grid[i] = std::exp(l0 + (l1 - l0) * static_cast<double>(i) / static_cast<double>(g - 1));
    cost[i] = coarse.project(grid[i]).residual_ss;
    if (cost[i] < cost[best]) best = i;
  }
  const double lo = grid[best == 0 ? 0 : best - 1];
  const double hi = grid[std::min(best + 1, grid.size() - 1)];
  std::uintmax_t iterations = 100;
  const auto r = boost::math::tools::brent_find_minima([&](double c3) { return data.project(c3).residual_ss; }, lo, hi,
                                                       o.brent_bits, iterations);
  return r.first;
}

// Robust sigma (1.4826 MAD) of a residual sample.
double robust_sigma(std::vector<double> r) {
  if (r.empty()) return 0.0;
  for (double& v : r) v = std::abs(v);
  auto mid = r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2);
  std::nth_element(r.begin(), mid, r.end());
  return 1.482602218505602 * *mid;
}

std::vector<double> residuals(const IntegratedData& d, const ScaledMem& m) {
  const std::vector<double> o = d.offsets(m.c1, m.c2, m.c3);
  std::vector<double> r(d.y.size());
  const double e = m.c3 + 1.0;
  for (std::size_t b = 0; b < d.groups(); ++b) {
    for (std::size_t k = d.group_begin[b]; k < d.group_begin[b + 1]; ++k) {
      r[k] = d.y[k] - o[b] - d.s[k] * (m.c1 * d.p[k] + m.c2 * detail::pow_from_log(d.log_p[k], e) / e);
    }
  }
  return r;
}

std::vector<double> residuals(const DerivativeData& d, const ScaledMem& m) {
  std::vector<double> r(d.z.size());
  for (std::size_t k = 0; k < d.z.size(); ++k) {
    r[k] = d.z[k] - m.c1 - m.c2 * detail::derivative_regressor(d.log_pa[k], d.log_pb[k], d.inv_dp[k], m.c3);
  }
  return r;
}

MemParams unscale(const ScaledMem& m, const Scales& sc) {
  MemParams p{};
  p.c1 = m.c1 * sc.y / sc.u;
  p.c2 = m.c2 * sc.y / std::pow(sc.u, m.c3 + 1.0);
  p.c3 = m.c3;
  return p;
}

// The physical range, with a sentence for the refusal ("" when fine).
std::string range_problem(const MemParams& p, const MemFitOptions& o) {
  if (!(p.c1 > 0.0)) return fmt::format("c1 = {:g} m/V: must be > 0 (the stage does not move with u)", p.c1);
  if (p.c2 < 0.0) return fmt::format("c2 = {:g}: must be >= 0 (the loop bends the wrong way for MEM)", p.c2);
  if (!(p.c3 > 0.0) || p.c3 > o.c3_max) return fmt::format("c3 = {:g}: must be in (0, {:g}]", p.c3, o.c3_max);
  if (p.c2 > 0.0 && (p.c3 >= o.c3_max * (1.0 - 1e-6) || p.c3 <= o.c3_min * (1.0 + 1e-6))) {
    return fmt::format("c3 = {:g} sits on the search bound [{:g}, {:g}]: the data do not determine it", p.c3, o.c3_min,
                       o.c3_max);
  }
  return check_valid(p, "").reason;
}

template <class Data>
MemFitResult solve(const Data& coarse, const Data& data, const Scales& sc, const MemFitOptions& o,
                   MemFitResult result) {
  // A stage that does not respond: y spans no more than its own noise. (The constrained fit
  // would otherwise return a tiny but "valid" slope.)
  if (sc.y_span < 20.0 * result.noise_rms_m) {
    const std::string why = fmt::format("y spans {:g} m, within its noise ({:g} m RMS): the stage does not move with u",
                                        sc.y_span, result.noise_rms_m);
    return refuse(std::move(result), FitStatus::out_of_range, why);
  }
  const double c3 = search_c3(coarse, data, o);
  const LinearPart lin = data.project(c3);
  ScaledMem m{lin.c1, lin.c2, c3};
  result.projected_c3 = c3;
  result.params = unscale(m, sc);
  result.constrained = lin.constrained;
  if (lin.constrained && lin.c2 == 0.0) {
    return refuse(std::move(result), FitStatus::out_of_range,
                  "separable least squares: c2 would be < 0: the loop bends the wrong way for MEM (its slope falls "
                  "with the distance from a reversal)");
  }
  if (std::string why = range_problem(result.params, o); !why.empty()) {
    return refuse(std::move(result), FitStatus::out_of_range, "separable least squares: " + why);
  }
  // On the domain's edge the unconstrained joint refinement would only walk back out of it.
  if (o.refine_with_ceres && !lin.constrained) {
    const double sigma = robust_sigma(residuals(data, m));
    const double scale = std::max(o.robust_scale_sigmas * sigma, 1e-12);
    const detail::RefineOutcome refined = detail::refine(data, m, o, scale);
    if (!refined.usable) {
      return refuse(std::move(result), FitStatus::solver_failure, "Ceres: " + refined.message);
    }
    m = refined.params;
    result.params = unscale(m, sc);
    if (std::string why = range_problem(result.params, o); !why.empty()) {
      return refuse(std::move(result), FitStatus::out_of_range, "robust refinement: " + why);
    }
  }
  result.status = FitStatus::ok;
  return result;
}

}  // namespace

MemFitResult fit_mem(std::span<const double> u, std::span<const double> y, const MemFitOptions& o) {
  o.validate();
  const FitTimer timer(o.clock);
  MemFitResult result;
  double umin = 0.0, umax = 0.0;
  if (FitCheck c = check_fit_input(u, y, o.min_input_range_V, &umin, &umax); !c.ok()) return timer.finish(result, c);
  const std::vector<BranchSegment> branches = split_branches(u, o.reversal_dead_band_V);
  result.branches_used = branches.size();
  if (branches.size() < o.min_branches) {
    return timer.finish(result, FitStatus::too_few_branches,
                        fmt::format("{} branches after the first reversal (need {}); the part before it is the "
                                    "skeleton curve and is not used",
                                    branches.size(), o.min_branches));
  }
  Scales sc;
  sc.u = 0.0;
  double ymin = y[branches.front().begin], ymax = ymin;
  for (const auto& b : branches) {
    for (std::size_t k = b.begin; k < b.end; ++k) {
      sc.u = std::max(sc.u, std::abs(u[k] - b.origin_u));
      ymin = std::min(ymin, y[k]);
      ymax = std::max(ymax, y[k]);
    }
  }
  if (!(sc.u > 0.0)) return timer.finish(result, FitStatus::constant_input, "u does not move after the first reversal");
  sc.y = ymax > ymin ? 0.5 * (ymax - ymin) : 1.0;
  sc.y_span = ymax - ymin;
  result.noise_rms_m = o.noise_rms_m > 0.0 ? o.noise_rms_m : estimate_noise_rms(y);

  if (o.form == MemFitForm::integrated) {
    const IntegratedData data = build_integrated(u, y, branches, sc, o);
    result.samples_used = data.y.size();
    if (result.samples_used < o.min_samples) {
      return timer.finish(result, FitStatus::too_few_samples,
                          fmt::format("{} samples on branches (need {})", result.samples_used, o.min_samples));
    }
    result = solve(build_integrated(u, y, branches, sc, o, kGridStride), data, sc, o, std::move(result));
  } else {
    // SNR of z = dy/du: |du| * slope / (sqrt(2) sigma_y); the slope is the loop's mean slope.
    const double slope = (ymax - ymin) / (umax - umin);
    const double min_du = slope > 0.0 ? o.min_snr * std::sqrt(2.0) * result.noise_rms_m / slope : 0.0;
    const DerivativeData data = build_derivative(u, y, branches, sc, min_du, o);
    result.samples_used = data.z.size();
    if (result.samples_used < o.min_samples) {
      return timer.finish(
          result, FitStatus::too_few_samples,
          fmt::format("{} difference points reach SNR {:g} (need {}; |du| must be >= {:g} V per {} samples)",
                      result.samples_used, o.min_snr, o.min_samples, min_du, o.derivative_lag));
    }
    result = solve(build_derivative(u, y, branches, sc, min_du, o, kGridStride), data, sc, o, std::move(result));
  }
  if (result.status == FitStatus::ok || result.status == FitStatus::out_of_range) {
    result.residual_rms_m = mem_branch_rms(u, y, branches, result.params);
  }
  if (result.ok()) {
    // A fit that is not a fit (NaN residual, c2 collapsed by overflow, ...) is a refusal.
    FitCheck c = check_valid(result.params, "MEM parameters outside their domain: ");
    if (c.ok()) c = check_fit_residual(result.residual_rms_m, sc.y_span);
    if (!c.ok()) result = refuse(std::move(result), c.status, c.reason);
  }
  return timer.stamp(std::move(result));
}

}  // namespace hystloop
