#include "ident/stage_fit.hpp"

#include <ceres/ceres.h>

#include <boost/math/tools/minima.hpp>

#include <Eigen/Dense>
#include <unsupported/Eigen/Polynomials>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <fmt/format.h>

#include "core/errors.hpp"

namespace hystloop {

void StageFitOptions::validate() const {
  if (!auto_order) {
    if (denominator_order < 1) throw ParameterError("denominator_order", "must be at least 1");
    if (numerator_order < 0) throw ParameterError("numerator_order", "must be >= 0");
    if (numerator_order > denominator_order) throw ParameterError("numerator_order", "must be <= denominator_order");
    if (zoh_sample_rate_Hz > 0.0 && numerator_order >= denominator_order) {
      throw ParameterError("numerator_order",
                           "must be < denominator_order with zoh_sample_rate_Hz > 0 (strictly proper)");
    }
  } else {
    if (max_order < 1 || max_order > 12) throw ParameterError("max_order", "must be in [1, 12]");
    if (relative_degree < 0) throw ParameterError("relative_degree", "must be >= 0");
    if (zoh_sample_rate_Hz > 0.0 && relative_degree < 1) {
      throw ParameterError("relative_degree", "must be >= 1 with zoh_sample_rate_Hz > 0 (strictly proper)");
    }
  }
  require_positive("chi2_accept", chi2_accept);
  if (denominator_order > 12) throw ParameterError("denominator_order", "must be <= 12");
  require_non_negative("sigma_dof", sigma_dof);
  if (sigma_dof > 0.0 && !(sigma_dof > 2.0)) throw ParameterError("sigma_dof", "must be 0 (exact) or > 2");
  require_non_negative("zoh_sample_rate_Hz", zoh_sample_rate_Hz);
  require_non_negative("max_delay_s", max_delay_s);
  if (delay_grid_points < 1) throw ParameterError("delay_grid_points", "must be at least 1");
  if (sk_iterations < 1) throw ParameterError("sk_iterations", "must be at least 1");
  if (max_refine_iterations < 1) throw ParameterError("max_refine_iterations", "must be at least 1");
}

namespace {

using C = std::complex<double>;

std::vector<C> roots_of(const std::vector<double>& ascending) {
  std::vector<C> r;
  if (ascending.size() < 2) return r;
  if (ascending.size() == 2) return {C(-ascending[0] / ascending[1], 0.0)};
  Eigen::VectorXd c(static_cast<Eigen::Index>(ascending.size()));
  for (std::size_t i = 0; i < ascending.size(); ++i) c[static_cast<Eigen::Index>(i)] = ascending[i];
  Eigen::PolynomialSolver<double, Eigen::Dynamic> solver;
  solver.compute(c);
  for (Eigen::Index i = 0; i < solver.roots().size(); ++i) r.push_back(solver.roots()[i]);
  std::sort(r.begin(), r.end(),
            [](C a, C b) { return std::abs(a) != std::abs(b) ? std::abs(a) < std::abs(b) : a.imag() < b.imag(); });
  return r;
}

// prod_i (1 - s / r_i), ascending (the constant term 1); the roots closed under conjugation.
std::vector<double> unit_polynomial(const std::vector<C>& roots) {
  std::vector<C> c{1.0};
  for (C r : roots) {
    std::vector<C> nc(c.size() + 1, 0.0);
    for (std::size_t i = 0; i < c.size(); ++i) nc[i] += c[i], nc[i + 1] -= c[i] / r;
    c = nc;
  }
  std::vector<double> out(c.size());
  for (std::size_t i = 0; i < c.size(); ++i) out[i] = c[i].real();
  return out;
}

C polyval(const std::vector<double>& ascending, C x) {
  C v = 0.0;
  for (std::size_t i = ascending.size(); i-- > 0;) v = v * x + ascending[i];
  return v;
}

// The model as poles, zeros and root-locus gain in s [rad/s], with a delay: both responses.
struct Zpk {
  std::vector<C> poles, zeros;
  double gain = 0.0, delay_s = 0.0;
  std::vector<C> residues;  // of the partial fractions (simple poles), for the ZOH response

  C rational(C s) const {
    C v = gain;
    for (C z : zeros) v *= s - z;
    for (C p : poles) v /= s - p;
    return v;
  }
  C continuous(double w) const { return rational(C(0.0, w)) * std::polar(1.0, -w * delay_s); }
  void prepare_residues() {
    residues.clear();
    for (std::size_t i = 0; i < poles.size(); ++i) {
      C r = gain;
      for (C z : zeros) r *= poles[i] - z;
      for (std::size_t j = 0; j < poles.size(); ++j)
        if (j != i) r /= poles[i] - poles[j];
      residues.push_back(r);
    }
  }
  // Exact ZOH response at hold period T (strictly proper, simple poles): each r / (s - p) held and
  // delayed by tau = l T + theta gives x[k+1] = e^{pT} x[k] + g0 u[k-l] + g1 u[k-l-1],
  // g0 = r (e^{p(T-theta)} - 1) / p, g1 = r e^{p(T-theta)} (e^{p theta} - 1) / p.
  C sampled(double w, double T) const {
    const double ticks = std::floor(delay_s / T + 1e-12);
    const double theta = std::max(0.0, delay_s - ticks * T);
    const C z = std::polar(1.0, w * T);
    C sum = 0.0;
    for (std::size_t i = 0; i < poles.size(); ++i) {
      const C p = poles[i];
      const C e = std::exp(p * (T - theta));
      const C g0 = residues[i] * (e - 1.0) / p;
      const C g1 = residues[i] * e * (std::exp(p * theta) - 1.0) / p;
      sum += (g0 + g1 / z) / (z - std::exp(p * T));
    }
    return sum * std::polar(1.0, -w * T * ticks);
  }
};

// The data, with s scaled by ws.
struct Prepared {
  std::vector<double> w;  // rad/s
  std::vector<C> G;
  std::vector<double> sigma;
  double ws = 1.0;
  double T = 0.0;  // hold period, 0 = continuous
};

// Coefficients in s~ = s / ws: b (m + 1), d (n + 1, d[0] = 1), tau [s].
struct Poly {
  std::vector<double> b, d;
  double tau_s = 0.0;
};

Zpk to_zpk(const Poly& p, double ws) {
  Zpk z;
  const std::size_t m = p.b.size() - 1, n = p.d.size() - 1;
  for (C r : roots_of(p.d)) z.poles.push_back(r * ws);
  for (C r : roots_of(p.b)) z.zeros.push_back(r * ws);
  z.gain = p.b[m] / p.d[n] * std::pow(ws, static_cast<double>(n) - static_cast<double>(m));
  z.delay_s = p.tau_s;
  return z;
}

// The model as fitted to the data at every line (ZOH'd when T > 0).
bool model_at_lines(const Poly& poly, const Prepared& pr, std::vector<C>& out) {
  out.resize(pr.w.size());
  if (pr.T > 0.0) {
    Zpk z = to_zpk(poly, pr.ws);
    z.prepare_residues();
    for (std::size_t k = 0; k < pr.w.size(); ++k) out[k] = z.sampled(pr.w[k], pr.T);
  } else {
    for (std::size_t k = 0; k < pr.w.size(); ++k) {
      const C s(0.0, pr.w[k] / pr.ws);
      out[k] = polyval(poly.b, s) / polyval(poly.d, s) * std::polar(1.0, -pr.w[k] * poly.tau_s);
    }
  }
  for (const C& v : out)
    if (!std::isfinite(v.real()) || !std::isfinite(v.imag())) return false;
  return true;
}

double weighted_cost(const Poly& poly, const Prepared& pr) {
  std::vector<C> m;
  if (!model_at_lines(poly, pr, m)) return std::numeric_limits<double>::infinity();
  double c = 0.0;
  for (std::size_t k = 0; k < m.size(); ++k) c += std::norm((pr.G[k] - m[k]) / pr.sigma[k]);
  return c;
}

struct SkFit {
  Poly poly;
  double cost = std::numeric_limits<double>::infinity();  // on the (ZOH-corrected) data SK sees
  double condition = 0.0;
  int iterations = 0;
};

// SK iterations for a given delay. With a hold, the data are first divided by its sinc and half a
// tick (the images are left: the refinement fits them exactly).
SkFit sk_fit(const Prepared& pr, int m, int n, bool unit_dc, double tau_s, int max_iterations, bool condition) {
  const std::size_t F = pr.w.size();
  std::vector<C> H(F), s(F);
  std::vector<double> wt(F);
  for (std::size_t k = 0; k < F; ++k) {
    C zoh = 1.0;
    if (pr.T > 0.0) {
      const double x = 0.5 * pr.w[k] * pr.T;
      zoh = std::sin(x) / x * std::polar(1.0, -x);
    }
    H[k] = pr.G[k] * std::polar(1.0, pr.w[k] * tau_s) / zoh;
    wt[k] = std::abs(zoh) / pr.sigma[k];
    s[k] = C(0.0, pr.w[k] / pr.ws);
  }
  const int b_first = unit_dc ? 1 : 0;
  const int nb = m + 1 - b_first, q = nb + n;
  SkFit fit;
  fit.poly.b.assign(static_cast<std::size_t>(m) + 1, 0.0);
  fit.poly.d.assign(static_cast<std::size_t>(n) + 1, 0.0);
  fit.poly.d[0] = 1.0;
  if (unit_dc) fit.poly.b[0] = 1.0;
  fit.poly.tau_s = tau_s;
  std::vector<double> d_prev_abs(F, 1.0);  // |D_prev|: 1 at the first (Levy) step
  Eigen::MatrixXd A(2 * F, q);
  Eigen::VectorXd rhs(2 * F);
  for (int it = 0; it < max_iterations; ++it) {
    for (std::size_t k = 0; k < F; ++k) {
      const double scale = wt[k] / d_prev_abs[k];
      C sp = 1.0;
      std::vector<C> row(static_cast<std::size_t>(q));
      for (int i = 0; i <= std::max(m, n); ++i) {
        if (i >= b_first && i <= m) row[static_cast<std::size_t>(i - b_first)] = sp * scale;
        if (i >= 1 && i <= n) row[static_cast<std::size_t>(nb + i - 1)] = -H[k] * sp * scale;
        sp *= s[k];
      }
      const C r = (H[k] - (unit_dc ? 1.0 : 0.0)) * scale;
      for (int j = 0; j < q; ++j) {
        A(static_cast<Eigen::Index>(2 * k), j) = row[static_cast<std::size_t>(j)].real();
        A(static_cast<Eigen::Index>(2 * k + 1), j) = row[static_cast<std::size_t>(j)].imag();
      }
      rhs(static_cast<Eigen::Index>(2 * k)) = r.real();
      rhs(static_cast<Eigen::Index>(2 * k + 1)) = r.imag();
    }
    const Eigen::VectorXd norms = A.colwise().norm().transpose().cwiseMax(1e-300);
    const Eigen::MatrixXd As = A * norms.cwiseInverse().asDiagonal();
    const Eigen::VectorXd x = As.colPivHouseholderQr().solve(rhs).cwiseQuotient(norms);
    if (!x.allFinite()) break;
    double change = 0.0;
    for (int i = 0; i < n; ++i) {
      const double v = x(nb + i);
      change =
          std::max(change, std::abs(v - fit.poly.d[static_cast<std::size_t>(i) + 1]) / std::max(std::abs(v), 1e-12));
      fit.poly.d[static_cast<std::size_t>(i) + 1] = v;
    }
    for (int i = 0; i < nb; ++i) fit.poly.b[static_cast<std::size_t>(i) + static_cast<std::size_t>(b_first)] = x(i);
    fit.iterations = it + 1;
    if (condition) {
      Eigen::JacobiSVD<Eigen::MatrixXd> svd(As);
      const auto& sv = svd.singularValues();
      fit.condition = sv(0) / sv(sv.size() - 1);
    }
    for (std::size_t k = 0; k < F; ++k) d_prev_abs[k] = std::max(std::abs(polyval(fit.poly.d, s[k])), 1e-300);
    if (change < 1e-10 && it > 0) break;
  }
  // Unstable poles mirrored into the left half plane (a stage is stable; |D(jw)| is unchanged).
  if (n >= 1 && fit.poly.d[static_cast<std::size_t>(n)] != 0.0) {
    std::vector<C> p = roots_of(fit.poly.d);
    bool flipped = false;
    for (C& r : p)
      if (r.real() > 0.0) r = C(-r.real(), r.imag()), flipped = true;
    if (flipped) fit.poly.d = unit_polynomial(p);  // d[0] = 1
  }
  double cost = 0.0;
  for (std::size_t k = 0; k < F; ++k) {
    cost += std::norm((polyval(fit.poly.b, s[k]) / polyval(fit.poly.d, s[k]) - H[k]) * wt[k]);
  }
  fit.cost = std::isfinite(cost) ? cost : std::numeric_limits<double>::infinity();
  return fit;
}

// SK profiled over the delay: the grid, then Brent on the best bracket.
SkFit sk_with_delay(const Prepared& pr, int m, int n, const StageFitOptions& o) {
  const int g = o.max_delay_s > 0.0 ? std::max(2, o.delay_grid_points) : 1;
  const double step = g > 1 ? o.max_delay_s / (g - 1) : 0.0;
  int best = 0;
  double best_cost = std::numeric_limits<double>::infinity();
  for (int i = 0; i < g; ++i) {
    const double c = sk_fit(pr, m, n, o.unit_dc_gain, step * i, o.sk_iterations, false).cost;
    if (c < best_cost) best_cost = c, best = i;
  }
  double tau = step * best;
  if (g > 1) {
    const double lo = step * std::max(0, best - 1), hi = step * std::min(g - 1, best + 1);
    std::uintmax_t iterations = 40;
    const auto r = boost::math::tools::brent_find_minima(
        [&](double t) { return sk_fit(pr, m, n, o.unit_dc_gain, t, o.sk_iterations, false).cost; }, lo, hi, 30,
        iterations);
    if (r.second < best_cost) tau = r.first;
  }
  return sk_fit(pr, m, n, o.unit_dc_gain, tau, o.sk_iterations, true);
}

// Ceres on the exact weighted residual: x = {free b, d1..dn, tau * ws}.
struct RefineResidual {
  const Prepared* pr;
  int m, n;
  bool unit_dc;
  Poly unpack(const double* x) const {
    Poly p;
    p.b.assign(static_cast<std::size_t>(m) + 1, 1.0);
    p.d.assign(static_cast<std::size_t>(n) + 1, 1.0);
    std::size_t j = 0;
    for (int i = unit_dc ? 1 : 0; i <= m; ++i) p.b[static_cast<std::size_t>(i)] = x[j++];
    for (int i = 1; i <= n; ++i) p.d[static_cast<std::size_t>(i)] = x[j++];
    p.tau_s = x[j] / pr->ws;
    return p;
  }
  bool operator()(double const* const* x, double* r) const {
    std::vector<C> model;
    if (!model_at_lines(unpack(x[0]), *pr, model)) return false;
    for (std::size_t k = 0; k < model.size(); ++k) {
      const C e = (pr->G[k] - model[k]) / pr->sigma[k];
      r[2 * k] = e.real(), r[2 * k + 1] = e.imag();
    }
    return true;
  }
};

bool refine(const Prepared& pr, int m, int n, const StageFitOptions& o, Poly& poly) {
  RefineResidual functor{&pr, m, n, o.unit_dc_gain};
  std::vector<double> x;
  for (int i = o.unit_dc_gain ? 1 : 0; i <= m; ++i) x.push_back(poly.b[static_cast<std::size_t>(i)]);
  for (int i = 1; i <= n; ++i) x.push_back(poly.d[static_cast<std::size_t>(i)]);
  x.push_back(poly.tau_s * pr.ws);
  auto* cost = new ceres::DynamicNumericDiffCostFunction<RefineResidual, ceres::CENTRAL>(new RefineResidual(functor),
                                                                                         ceres::TAKE_OWNERSHIP);
  cost->AddParameterBlock(static_cast<int>(x.size()));
  cost->SetNumResiduals(static_cast<int>(2 * pr.w.size()));
  ceres::Problem problem;
  problem.AddResidualBlock(cost, nullptr, x.data());
  problem.SetParameterLowerBound(x.data(), static_cast<int>(x.size() - 1), 0.0);
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = o.max_refine_iterations;
  so.logging_type = ceres::SILENT;
  so.function_tolerance = 1e-12;
  so.parameter_tolerance = 1e-12;
  so.gradient_tolerance = 1e-14;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  if (!summary.IsSolutionUsable()) return false;
  const Poly refined = functor.unpack(x.data());
  if (!(weighted_cost(refined, pr) <= weighted_cost(poly, pr))) return false;
  poly = refined;
  return true;
}

// A zero and its mirror image across the imaginary axis give the same |N(jw)|, and well below the
// zero their phases differ by nearly a delay's: 2 Re(z) w / |z|^2. SK's profile settles the delay
// first and the refinement cannot carry a real zero through infinity to the other half plane, so a
// fit can end in the minimum that trades a right-half-plane zero for its mirror and more delay
// (seen: a stage with a zero at +3 kHz and a tick of delay fitted with -3.1 kHz and two ticks, 19 deg
// off at 3 kHz). Each zero within reach of the band (real, or a complex pair together), and all of
// them at once, is mirrored with the delay moved to keep the low-frequency phase, refined, and the
// lowest weighted cost kept.
void try_mirrored_zeros(const Prepared& pr, int m, int n, const StageFitOptions& o, Poly& poly) {
  if (m < 1 || poly.b[0] == 0.0 || !(o.max_delay_s > 0.0)) return;
  const std::vector<C> zeros = roots_of(poly.b);  // in s~ = s / ws; ws is the band's top
  std::vector<std::vector<std::size_t>> groups;   // a real zero, or the upper member of a pair with its conjugate
  for (std::size_t i = 0; i < zeros.size(); ++i) {
    if (std::abs(zeros[i]) > 4.0 || zeros[i].imag() < 0.0) continue;
    if (zeros[i].imag() == 0.0) {
      groups.push_back({i});
      continue;
    }
    std::size_t mate = zeros.size();
    for (std::size_t j = 0; j < zeros.size(); ++j)
      if (j != i && std::abs(zeros[j] - std::conj(zeros[i])) <= 1e-9 * std::abs(zeros[i])) mate = j;
    if (mate < zeros.size()) groups.push_back({i, mate});
  }
  if (groups.empty()) return;
  std::vector<std::vector<std::size_t>> candidates = groups;
  if (groups.size() > 1) {
    candidates.emplace_back();
    for (const auto& g : groups) candidates.back().insert(candidates.back().end(), g.begin(), g.end());
  }
  double best_cost = weighted_cost(poly, pr);
  for (const auto& flip : candidates) {
    std::vector<C> z = zeros;
    double tau = poly.tau_s;
    for (std::size_t i : flip) {
      tau += 2.0 * z[i].real() / (std::norm(z[i]) * pr.ws);
      z[i] = C(-z[i].real(), z[i].imag());
    }
    if (!(tau >= 0.0 && tau <= o.max_delay_s)) continue;
    Poly trial = poly;  // b0 prod(1 - s~ / z_i): the same DC gain
    trial.b = unit_polynomial(z);
    for (double& b : trial.b) b *= poly.b[0];
    trial.tau_s = tau;
    refine(pr, m, n, o, trial);
    const double cost = weighted_cost(trial, pr);
    if (cost < best_cost) best_cost = cost, poly = trial;
  }
}

int parameter_count(int m, int n, bool unit_dc) { return (m + 1 - (unit_dc ? 1 : 0)) + n + 1; }

StageFitResult fit_order(const Prepared& pr, int m, int n, const StageFitOptions& o) {
  StageFitResult res;
  res.numerator_order = m, res.denominator_order = n;
  res.zoh_sample_rate_Hz = o.zoh_sample_rate_Hz;
  res.chi2_expected = o.sigma_dof > 0.0 ? o.sigma_dof / (o.sigma_dof - 2.0) : 1.0;
  const std::size_t F = pr.w.size();
  const int p = parameter_count(m, n, o.unit_dc_gain);
  if (static_cast<double>(F) < static_cast<double>(p)) {
    res.status = FitStatus::too_few_samples;
    res.reason =
        fmt::format("frequency_Hz: {} lines cannot determine {} parameters (orders {}/{} and the delay)", F, p, m, n);
    return res;
  }
  SkFit sk = sk_with_delay(pr, m, n, o);
  res.sk_condition = sk.condition;
  res.sk_iterations_used = sk.iterations;
  Poly poly = sk.poly;
  if (!std::isfinite(weighted_cost(poly, pr))) {
    res.status = FitStatus::solver_failure;
    res.reason = "the SK iterations gave no finite model";
    return res;
  }
  if (o.refine) {
    res.refined = refine(pr, m, n, o, poly);
    try_mirrored_zeros(pr, m, n, o, poly);
  }
  // The result in s [rad/s].
  const Zpk z = to_zpk(poly, pr.ws);
  res.poles_rad_s = z.poles, res.zeros_rad_s = z.zeros, res.gain = z.gain, res.delay_s = poly.tau_s;
  res.dc_gain = poly.b[0];
  for (std::size_t i = 0; i < poly.b.size(); ++i)
    res.numerator.push_back(poly.b[i] / std::pow(pr.ws, static_cast<double>(i)));
  for (std::size_t i = 0; i < poly.d.size(); ++i)
    res.denominator.push_back(poly.d[i] / std::pow(pr.ws, static_cast<double>(i)));
  std::vector<C> model;
  model_at_lines(poly, pr, model);
  res.cost = 0.0;
  for (std::size_t k = 0; k < F; ++k) {
    res.residual.push_back(pr.G[k] - model[k]);
    res.weighted_residual.push_back(std::abs(res.residual.back()) / pr.sigma[k]);
    res.cost += res.weighted_residual.back() * res.weighted_residual.back();
  }
  res.chi2_per_line = res.cost / (static_cast<double>(F) - 0.5 * static_cast<double>(p));
  if (!std::isfinite(res.cost)) {
    res.status = FitStatus::solver_failure;
    res.reason = "the fitted model's residual is not finite";
    return res;
  }
  for (C pole : res.poles_rad_s) {
    if (!(pole.real() < 0.0)) {
      res.status = FitStatus::out_of_range;
      res.reason = fmt::format("unstable pole {:g}{:+g}j rad/s: the data do not hold a stable model of orders {}/{}",
                               pole.real(), pole.imag(), m, n);
      return res;
    }
  }
  res.order_consistent = res.chi2_per_line <= o.chi2_accept * res.chi2_expected;
  res.status = FitStatus::ok;
  return res;
}

StageFitResult refuse(FitStatus s, std::string why) {
  StageFitResult r;
  r.status = s;
  r.reason = std::move(why);
  return r;
}

}  // namespace

std::complex<double> StageFitResult::model_response(double f_Hz) const {
  Zpk z{poles_rad_s, zeros_rad_s, gain, delay_s, {}};
  return z.continuous(2.0 * std::numbers::pi * f_Hz);
}

std::complex<double> StageFitResult::sampled_response(double f_Hz) const {
  if (!(zoh_sample_rate_Hz > 0.0)) return model_response(f_Hz);
  Zpk z{poles_rad_s, zeros_rad_s, gain, delay_s, {}};
  z.prepare_residues();
  return z.sampled(2.0 * std::numbers::pi * f_Hz, 1.0 / zoh_sample_rate_Hz);
}

StageFitResult fit_stage_model(const StageFitData& data, const StageFitOptions& o) {
  o.validate();
  const std::size_t F = data.frequency_Hz.size();
  if (F == 0) return refuse(FitStatus::size_mismatch, "frequency_Hz is empty");
  if (data.G.size() != F || data.sigma.size() != F) {
    return refuse(FitStatus::size_mismatch, fmt::format("frequency_Hz has {} lines, G {} and sigma {}: they must agree",
                                                        F, data.G.size(), data.sigma.size()));
  }
  Prepared pr;
  pr.T = o.zoh_sample_rate_Hz > 0.0 ? 1.0 / o.zoh_sample_rate_Hz : 0.0;
  double f_max = 0.0;
  for (std::size_t k = 0; k < F; ++k) {
    const double f = data.frequency_Hz[k], s = data.sigma[k];
    const C g = data.G[k];
    if (!std::isfinite(f)) return refuse(FitStatus::non_finite_data, fmt::format("frequency_Hz[{}] is not finite", k));
    if (!std::isfinite(g.real()) || !std::isfinite(g.imag()))
      return refuse(FitStatus::non_finite_data, fmt::format("G[{}] is not finite", k));
    if (!std::isfinite(s)) return refuse(FitStatus::non_finite_data, fmt::format("sigma[{}] is not finite", k));
    if (!(s > 0.0)) return refuse(FitStatus::out_of_range, fmt::format("sigma[{}] = {:g}: must be > 0", k, s));
    if (!(f > 0.0)) return refuse(FitStatus::out_of_range, fmt::format("frequency_Hz[{}] = {:g}: must be > 0", k, f));
    if (pr.T > 0.0 && !(f < 0.5 * o.zoh_sample_rate_Hz)) {
      return refuse(FitStatus::out_of_range,
                    fmt::format("frequency_Hz[{}] = {:g}: must be below Nyquist of zoh_sample_rate_Hz", k, f));
    }
    pr.w.push_back(2.0 * std::numbers::pi * f);
    pr.G.push_back(g);
    pr.sigma.push_back(s);
    f_max = std::max(f_max, f);
  }
  pr.ws = 2.0 * std::numbers::pi * f_max;
  if (!o.auto_order) return fit_order(pr, o.numerator_order, o.denominator_order, o);

  std::vector<StageOrderTrial> trials;
  StageFitResult best;
  bool have_best = false;
  for (int n = 1; n <= o.max_order; ++n) {
    const int m = std::max(0, n - o.relative_degree);
    if (pr.T > 0.0 && m >= n) continue;
    StageFitResult r = fit_order(pr, m, n, o);
    if (r.status == FitStatus::too_few_samples) break;
    StageOrderTrial t{m, n, r.chi2_per_line, r.ok() && r.chi2_per_line <= o.chi2_accept * r.chi2_expected};
    trials.push_back(t);
    if (r.ok() && (!have_best || r.chi2_per_line < best.chi2_per_line)) best = std::move(r), have_best = true;
    if (t.accepted) {
      best.orders = trials;
      return best;
    }
  }
  if (!have_best) {
    return refuse(FitStatus::too_few_samples,
                  fmt::format("no order up to max_order = {} gave a usable model from {} lines", o.max_order, F));
  }
  best.orders = trials;
  best.reason = fmt::format(
      "no order up to max_order = {} is consistent with sigma: best chi-square per line {:g} (orders {}/{}), "
      "expected {:g}",
      o.max_order, best.chi2_per_line, best.numerator_order, best.denominator_order, best.chi2_expected);
  return best;
}

}  // namespace hystloop
