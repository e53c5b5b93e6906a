#include "ident/banning_fit.hpp"

#include <ceres/ceres.h>

#include <boost/math/tools/minima.hpp>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <limits>
#include <numbers>
#include <fmt/format.h>

#include "core/errors.hpp"
#include "ident/ceres_budget.hpp"
#include "ident/fit_checks.hpp"
#include "models/coleman_hodgdon.hpp"

namespace hystloop {

void BanningFitOptions::validate() const {
  require_positive("frequency_threshold_Hz", frequency_threshold_Hz);
  require_positive("small_amplitude_max_V", small_amplitude_max_V);
  require_non_negative("min_offset_span_V", min_offset_span_V);
  loop.validate();
  require_positive("max_solver_time_s", max_solver_time_s);
}

namespace {

struct SineFit {
  double offset = 0.0, amplitude = 0.0, rss = 0.0;
  double phase = 0.0;  // x = offset + amplitude sin(w k + phase)
};

// Least squares x = c0 + cs sin(w k) + cc cos(w k) at a given frequency.
SineFit sine_fit(std::span<const double> x, double f, double fs) {
  Eigen::Matrix3d g = Eigen::Matrix3d::Zero();
  Eigen::Vector3d r = Eigen::Vector3d::Zero();
  double xx = 0.0;
  const double w = 2.0 * std::numbers::pi * f / fs;
  for (std::size_t k = 0; k < x.size(); ++k) {
    const Eigen::Vector3d phi(1.0, std::sin(w * static_cast<double>(k)), std::cos(w * static_cast<double>(k)));
    g += phi * phi.transpose();
    r += phi * x[k];
    xx += x[k] * x[k];
  }
  const Eigen::Vector3d c = g.ldlt().solve(r);
  return {c[0], std::hypot(c[1], c[2]), xx - c.dot(r), std::atan2(c[2], c[1])};
}

// (21) and (24) of Theorem 3: the loop's peak-to-peak slope and its area at amplitude amp [V]
// (T: a double, or Ceres' Jet where b and alpha are fitted).
template <class T>
T ch_slope(T a, T b, T alpha, T amp) {
  using std::tanh;
  return a + (b - a) / alpha * tanh(alpha * amp) / amp;
}
template <class T>
T ch_area(T a, T b, T alpha, T amp) {
  using std::tanh;
  return T(4.0) * (a - b) / alpha * (amp - tanh(alpha * amp) / alpha);
}

// The sine at frequency f fitted to u: its offset and amplitude.
SineEstimate sine_at(std::span<const double> u, double f, double fs) {
  const SineFit fit = sine_fit(u, f, fs);
  return {fit.offset, fit.amplitude, f, std::isfinite(fit.amplitude) && fit.amplitude > 0.0};
}

}  // namespace

SineEstimate estimate_sine(std::span<const double> u, double fs, bool refine_frequency) {
  SineEstimate e;
  if (u.size() < 8 || !(fs > 0.0)) return e;
  const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
  const double mid = 0.5 * (*lo + *hi);
  if (!(*hi > *lo)) return e;
  // Crossings of the mid level, interpolated: half a period apart.
  double first = -1.0, last = -1.0;
  std::size_t count = 0;
  for (std::size_t k = 1; k < u.size(); ++k) {
    const double a = u[k - 1] - mid, b = u[k] - mid;
    if ((a < 0.0 && b >= 0.0) || (a > 0.0 && b <= 0.0)) {
      const double t = (static_cast<double>(k - 1) + a / (a - b)) / fs;
      if (count == 0) first = t;
      last = t;
      ++count;
    }
  }
  if (count < 3 || !(last > first)) return e;
  // Linear interpolation of the crossings is biased at a few samples per period: refine the
  // frequency by minimising the least-squares residual of the sine fit around it.
  const double f0 = static_cast<double>(count - 1) / (2.0 * (last - first));
  if (!refine_frequency) return sine_at(u, f0, fs);
  std::uintmax_t iterations = 60;
  const auto best = boost::math::tools::brent_find_minima([&](double f) { return sine_fit(u, f, fs).rss; },
                                                          f0 * (1.0 - 2e-3), f0 * (1.0 + 2e-3), 40, iterations);
  return sine_at(u, best.first, fs);
}

double first_harmonic_amplitude(std::span<const double> y, double f, double fs) { return sine_fit(y, f, fs).amplitude; }

std::complex<double> stage_response_model(double k, double c, double omega, double T) noexcept {
  using C = std::complex<double>;
  if (!(T > 0.0)) return k / C(k - omega * omega, c * omega);
  // Exact ZOH: exp of the augmented [A B; 0 0] T gives Phi and Gamma at once.
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  m(0, 1) = 1.0;
  m(1, 0) = -k;
  m(1, 1) = -c;
  m(1, 2) = k;
  const Eigen::Matrix3d e = (m * T).exp();
  const C z = std::polar(1.0, omega * T);
  // (z I - Phi)^{-1} Gamma, first row (y = x_0).
  const C a00 = z - e(0, 0), a01 = -e(0, 1), a10 = -e(1, 0), a11 = z - e(1, 1);
  const C det = a00 * a11 - a01 * a10;
  return (a11 * e(0, 2) - a01 * e(1, 2)) / det;
}

double stage_magnitude_model(double k, double c, double omega, double T) noexcept {
  return std::abs(stage_response_model(k, c, omega, T));
}

double loop_lag_area_per_rad(const ColemanHodgdonParams& h, double offset_V, double amplitude_V) {
  // Starts at the loop's lower tip, which Theorem 3 places at (offset - A, a offset - slope A),
  // so that the loop is periodic from the start (from inside it, it would settle only as
  // exp(-2 alpha A) a half period); the second period is integrated. 4096 steps a period: the
  // model is exact per step, the sum a midpoint rule.
  constexpr int kSteps = 4096;
  const double dth = 2.0 * std::numbers::pi / kSteps;
  ColemanHodgdon ch(h);
  const double slope = ch_slope(h.a, h.b, h.alpha, amplitude_V);
  ch.reset(offset_V - amplitude_V, h.a * offset_V - slope * amplitude_V);
  double integral = 0.0;
  double w_prev = ch.output(), u_prev = offset_V - amplitude_V;
  for (int k = 1; k <= 2 * kSteps; ++k) {
    const double u = offset_V - amplitude_V * std::cos(dth * k);
    const double w = ch.step(u);
    if (k > kSteps) integral += (w - w_prev) * (u - u_prev) / dth;
    w_prev = w, u_prev = u;
  }
  return integral;
}

namespace {

// A loop's slope (21) or area (24), relative to the measured one, with b in nm/V (x[0]) and alpha
// in 1/V (x[1]); a fixed.
struct LoopResidual {
  double a_nm, amplitude, measured;  // [nm/V] or [nm V]
  bool area;
  template <class T>
  bool operator()(const T* x, T* r) const {
    const T model = area ? ch_area(T(a_nm), x[0], x[1], T(amplitude)) : ch_slope(T(a_nm), x[0], x[1], T(amplitude));
    r[0] = (model - T(measured)) / T(measured);
    return true;
  }
};

struct MagnitudeResidual {
  double omega, magnitude, sample_time;
  bool operator()(const double* x, double* r) const {
    r[0] = (stage_magnitude_model(std::exp(x[0]), std::exp(x[1]), omega, sample_time) - magnitude) / magnitude;
    return true;
  }
};

// Every solve of the fit: these tolerances, the time budget read from the fit's clock.
ceres::Solver::Summary solve(ceres::Problem& problem, const FitClock& clock, double budget_s) {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::DENSE_QR;
  o.max_num_iterations = 200;
  o.logging_type = ceres::SILENT;
  o.function_tolerance = 1e-14;
  o.parameter_tolerance = 1e-12;
  o.gradient_tolerance = 1e-16;
  detail::CeresTimeBudget budget(clock, budget_s);
  budget.attach(o);
  ceres::Solver::Summary summary;
  ceres::Solve(o, &problem, &summary);
  return summary;
}

// Inverts (25) for h (paper order): ptp = 2 a h A + 2 (b - a)/alpha tanh(alpha A h), increasing in h.
double invert_peak_to_peak(const ColemanHodgdonParams& p, double ptp, double amp) {
  auto f = [&](double h) {
    return 2.0 * p.a * h * amp + 2.0 * (p.b - p.a) / p.alpha * std::tanh(p.alpha * amp * h) - ptp;
  };
  double lo = 0.0, hi = 1.0;
  while (f(hi) < 0.0 && hi < 1e6) hi *= 2.0;
  for (int i = 0; i < 100; ++i) {
    const double m = 0.5 * (lo + hi);
    (f(m) < 0.0 ? lo : hi) = m;
  }
  return 0.5 * (lo + hi);
}

using PointRefs = std::vector<BanningPoint*>;

// Small loops seed b; the larger ones' areas give alpha. The amplitude is read from noisy data:
// one at the bound (the plan's 5 V) must not move between the sets from run to run.
bool small_loop(const BanningPoint& p, const BanningFitOptions& o) {
  return p.amplitude_V <= o.small_amplitude_max_V * 1.01;
}

// Phase of b behind a, in [-pi, pi].
double phase_behind(double a, double b) { return std::remainder(a - b, 2.0 * std::numbers::pi); }

// 1. Offset, amplitude and frequency of every experiment's input; loop features of the slow
// ones, the first-harmonic magnitude of the fast ones. An experiment that is not a sine is
// skipped with a note; one with bad samples refuses the whole fit.
FitCheck measure_experiments(std::span<const BanningExperimentData> experiments, const BanningFitOptions& o,
                             std::vector<BanningPoint>& points) {
  for (std::size_t i = 0; i < experiments.size(); ++i) {
    const auto& ex = experiments[i];
    BanningPoint pt;
    if (FitCheck c = check_fit_samples(ex.u, ex.y); !c.ok()) {
      return FitCheck{c.status, "experiment " + std::to_string(i) + ": " + c.reason};
    }
    SineEstimate se;
    if (ex.frequency_Hz > 0.0) {
      se = sine_at(ex.u, ex.frequency_Hz, ex.sample_rate_Hz);
    } else {
      se = estimate_sine(ex.u, ex.sample_rate_Hz, false);
      if (se.ok && se.frequency_Hz >= o.frequency_threshold_Hz) se = estimate_sine(ex.u, ex.sample_rate_Hz, true);
    }
    if (!se.ok) {
      pt.note = "input is not a sine of at least one period";
      points.push_back(pt);
      continue;
    }
    pt.offset_V = se.offset, pt.amplitude_V = se.amplitude, pt.frequency_Hz = se.frequency_Hz;
    pt.magnitude_experiment = se.frequency_Hz >= o.frequency_threshold_Hz;
    if (pt.magnitude_experiment) {
      const SineFit yu = sine_fit(ex.u, se.frequency_Hz, ex.sample_rate_Hz);
      const SineFit yf = sine_fit(ex.y, se.frequency_Hz, ex.sample_rate_Hz);
      pt.response_m = yf.amplitude;
      pt.phase_lag_rad = phase_behind(yu.phase, yf.phase);
      pt.used = true;
    } else {
      const LoopFeatureResult lf = extract_loop_features(ex.u, ex.y, o.loop);
      if (!lf.ok()) {
        pt.note = std::string("loop features: ") + std::string(describe(lf.status));
      } else {
        pt.features = lf.features;
        pt.used = true;
      }
    }
    points.push_back(pt);
  }
  return {};
}

// 2. a: the least-squares line y_centre = a u_centre + const through the loop centres.
FitCheck fit_centre_line(const PointRefs& loops, const BanningFitOptions& o, BanningFitResult& res) {
  double umin = 1e300, umax = -1e300;
  for (const auto* p : loops) umin = std::min(umin, p->features.u_centre), umax = std::max(umax, p->features.u_centre);
  if (loops.size() < 2 || umax - umin < o.min_offset_span_V) {
    return FitCheck{FitStatus::too_few_samples,
                    fmt::format("{} usable loop experiments whose centres span {:g} V; need two or more offsets "
                                "spanning >= {:g} V to identify a",
                                loops.size(), loops.empty() ? 0.0 : umax - umin, o.min_offset_span_V)};
  }
  Eigen::Matrix2d g = Eigen::Matrix2d::Zero();
  Eigen::Vector2d r = Eigen::Vector2d::Zero();
  for (const auto* p : loops) {
    const Eigen::Vector2d phi(p->features.u_centre, 1.0);
    g += phi * phi.transpose();
    r += phi * p->features.y_centre;
  }
  const Eigen::Vector2d c = g.ldlt().solve(r);
  res.hysteresis.a = c[0];
  double ss = 0.0;
  for (const auto* p : loops) ss += std::pow(p->features.y_centre - c[0] * p->features.u_centre - c[1], 2);
  res.centre_rms_m = std::sqrt(ss / static_cast<double>(loops.size()));
  return {};
}

// 3. Seeds: b from the mean small-loop slope (Theorem 2), alpha as the median of the
// small-amplitude area formula 4/3 (a - b) alpha A^3 over the larger loops. x = {b [nm/V], alpha}.
FitCheck seed_b_alpha(const PointRefs& loops, double a, const BanningFitOptions& o, double x[2]) {
  double b0 = 0.0;
  std::size_t n = 0;
  for (const auto* p : loops) {
    if (small_loop(*p, o)) b0 += p->features.slope, ++n;
  }
  if (n == 0) {  // no small loop: the smallest one
    b0 = (*std::min_element(loops.begin(), loops.end(), [](auto* l, auto* r) {
           return l->amplitude_V < r->amplitude_V;
         }))->features.slope;
    n = 1;
  }
  b0 /= static_cast<double>(n);
  if (!(a > 0.0) || !(b0 > 0.0) || !(b0 < a)) {
    return FitCheck{
        FitStatus::out_of_range,
        fmt::format("a = {:g} m/V, small-loop slope b = {:g} m/V: need 0 < b < a (a loop with area)", a, b0)};
  }
  std::vector<double> alphas;
  for (const auto* p : loops) {
    if (p->area_fitted && p->features.area > 0.0) {
      alphas.push_back(3.0 * p->features.area / (4.0 * (a - b0) * std::pow(p->amplitude_V, 3)));
    }
  }
  if (alphas.empty()) {
    return FitCheck{FitStatus::too_few_samples,
                    "no loop above small_amplitude_max_V with a positive area: alpha cannot be identified"};
  }
  std::nth_element(alphas.begin(), alphas.begin() + static_cast<std::ptrdiff_t>(alphas.size() / 2), alphas.end());
  x[0] = b0 * 1e9, x[1] = alphas[alphas.size() / 2];
  return {};
}

// 4. (b, alpha) jointly on the exact (21) for every slope and (24) for the larger areas.
FitCheck refine_b_alpha(const PointRefs& loops, const BanningFitOptions& o, const FitClock& clock, double x[2],
                        BanningFitResult& res) {
  const double a = res.hysteresis.a;
  ceres::Problem problem;
  for (const auto* p : loops) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<LoopResidual, 1, 2>(
                                 new LoopResidual{a * 1e9, p->amplitude_V, p->features.slope * 1e9, false}),
                             nullptr, x);
    if (p->area_fitted) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<LoopResidual, 1, 2>(new LoopResidual{
                                   a * 1e9, p->amplitude_V, (p->features.area + p->lag_area) * 1e9, true}),
                               nullptr, x);
    }
  }
  problem.SetParameterLowerBound(x, 0, 1e-6);
  problem.SetParameterLowerBound(x, 1, 1e-9);
  const ceres::Solver::Summary summary = solve(problem, clock, o.max_solver_time_s);
  if (!summary.IsSolutionUsable()) return FitCheck{FitStatus::solver_failure, "Ceres (b, alpha): " + summary.message};
  res.hysteresis.b = x[0] * 1e-9;
  res.hysteresis.alpha = x[1];
  if (FitCheck c = check_valid(res.hysteresis, "hysteresis: "); !c.ok()) return c;
  const double b = res.hysteresis.b, al = res.hysteresis.alpha;
  double ss = 0.0, sa = 0.0;
  std::size_t na = 0;
  for (const auto* p : loops) {
    const double A = p->amplitude_V;
    ss += std::pow((ch_slope(a, b, al, A) - p->features.slope) / p->features.slope, 2);
    if (p->area_fitted) {
      const double area = p->features.area + p->lag_area;
      sa += std::pow((ch_area(a, b, al, A) - area) / area, 2), ++na;
    }
  }
  res.slope_rel_rms = std::sqrt(ss / static_cast<double>(loops.size()));
  res.area_rel_rms = na ? std::sqrt(sa / static_cast<double>(na)) : 0.0;
  if (!std::isfinite(res.slope_rel_rms) || !std::isfinite(res.area_rel_rms)) {
    return FitCheck{FitStatus::solver_failure, "the slope or area residual is not finite: no usable solution"};
  }
  return {};
}

// 5. k, c: each magnitude experiment's h(w) through (27) (in the chosen order), then the
// stage's magnitude response fitted by Ceres, seeded at the peak.
FitCheck fit_stage(const PointRefs& mags, double sample_rate_Hz, const BanningFitOptions& o, const FitClock& clock,
                   BanningFitResult& res) {
  const ColemanHodgdonParams& h = res.hysteresis;
  double peak_h = 0.0, peak_f = 0.0;
  for (auto* p : mags) {
    const double ptp = 2.0 * p->response_m;
    if (o.order == BanningOrder::kStageThenHysteresis) {
      p->magnitude = invert_peak_to_peak(h, ptp, p->amplitude_V);
    } else {  // hysteresis first: the stage sees a loop of slope (21) at the drive amplitude
      p->magnitude = ptp / (2.0 * ch_slope(h.a, h.b, h.alpha, p->amplitude_V) * p->amplitude_V);
    }
    if (p->magnitude > peak_h) peak_h = p->magnitude, peak_f = p->frequency_Hz;
  }
  // Seed: resonance at the peak, damping from its height (h_peak ~ 1 / (2 zeta)).
  const double wp = 2.0 * std::numbers::pi * peak_f;
  double kc[2] = {std::log(wp * wp), std::log(peak_h > 1.2 ? wp / peak_h : wp)};
  ceres::Problem problem;
  for (const auto* p : mags) {
    problem.AddResidualBlock(
        new ceres::NumericDiffCostFunction<MagnitudeResidual, ceres::CENTRAL, 1, 2>(new MagnitudeResidual{
            2.0 * std::numbers::pi * p->frequency_Hz, p->magnitude, o.zoh_magnitude ? 1.0 / sample_rate_Hz : 0.0}),
        nullptr, kc);
  }
  const ceres::Solver::Summary summary = solve(problem, clock, o.max_solver_time_s);
  if (!summary.IsSolutionUsable()) return FitCheck{FitStatus::solver_failure, "Ceres (k, c): " + summary.message};
  res.stage.k = std::exp(kc[0]);
  res.stage.c = std::exp(kc[1]);
  if (FitCheck c = check_valid(res.stage, "stage: "); !c.ok()) return c;
  res.magnitude_rel_rms = std::sqrt(2.0 * summary.final_cost / static_cast<double>(mags.size()));
  if (!std::isfinite(res.magnitude_rel_rms)) {
    return FitCheck{FitStatus::solver_failure, "the magnitude residual is not finite: no usable solution"};
  }
  return {};
}

// 6. The lag. Below f_n / 2 each magnitude experiment's phase, less the stage model's, is fitted
// by phi0 + w tau: phi0 the small loop's own phase (rate independent), tau what the model lacks
// (the sampling's pairing of u and y, a sensor's delay). Each loop's area is then corrected by
// what the lag at its frequency, stage and delay, added to it (or, a lead, took from it).
// Refused (areas as measured, with a note) without two such experiments an octave apart, or when
// the lag is too large for the first-order correction.
void correct_for_lag(const PointRefs& loops, const PointRefs& mags, double sample_rate_Hz, const BanningFitOptions& o,
                     BanningFitResult& res) {
  constexpr double kMaxLoopLag_rad = 0.05;
  const double T = o.zoh_magnitude ? 1.0 / sample_rate_Hz : 0.0;
  const double k = res.stage.k, c = res.stage.c;
  const double w_limit = 0.5 * res.stage.natural_frequency();
  auto stage_lag = [&](double w) { return -std::arg(stage_response_model(k, c, w, T)); };
  Eigen::Matrix2d g = Eigen::Matrix2d::Zero();
  Eigen::Vector2d r = Eigen::Vector2d::Zero();
  std::size_t n = 0;
  double w_lo = std::numeric_limits<double>::infinity(), w_hi = 0.0;
  for (const auto* p : mags) {
    const double w = 2.0 * std::numbers::pi * p->frequency_Hz;
    if (!(w < w_limit)) continue;
    const Eigen::Vector2d phi(1.0, w);
    g += phi * phi.transpose();
    r += phi * (p->phase_lag_rad - stage_lag(w));
    ++n, w_lo = std::min(w_lo, w), w_hi = std::max(w_hi, w);
  }
  if (n < 2 || !(w_hi >= 2.0 * w_lo)) {
    res.lag_note = "fewer than 2 magnitude experiments below f_n/2 an octave apart: areas not corrected for the lag";
    return;
  }
  const Eigen::Vector2d x = g.ldlt().solve(r);
  double ss = 0.0;
  for (const auto* p : mags) {
    const double w = 2.0 * std::numbers::pi * p->frequency_Hz;
    if (w < w_limit) ss += std::pow(p->phase_lag_rad - stage_lag(w) - x[0] - x[1] * w, 2);
  }
  double worst = 0.0;
  for (const auto* p : loops) {
    const double w = 2.0 * std::numbers::pi * p->frequency_Hz;
    worst = std::max(worst, std::abs(stage_lag(w) + w * x[1]));
  }
  if (!std::isfinite(x[1]) || !(worst <= kMaxLoopLag_rad)) {
    res.lag_note = fmt::format(
        "the lag at the loops' frequency is {:g} rad (delay {:g} s beyond the stage): too large to correct the areas "
        "to first order; measure slower loops",
        worst, x[1]);
    return;
  }
  res.lag_identified = true;
  res.delay_s = x[1];
  res.lag_experiments = n;
  res.lag_phase_rms_rad = std::sqrt(ss / static_cast<double>(n));
  for (auto* p : loops) {
    const double w = 2.0 * std::numbers::pi * p->frequency_Hz;
    p->lag_rad = stage_lag(w) + w * x[1];
    // A lag widens the (counter-clockwise) loop, a lead narrows it.
    p->lag_area = -p->lag_rad * loop_lag_area_per_rad(res.hysteresis, p->offset_V, p->amplitude_V);
  }
}

}  // namespace

BanningFitResult fit_banning(std::span<const BanningExperimentData> experiments, const BanningFitOptions& o) {
  o.validate();
  const FitTimer timer(o.clock);
  BanningFitResult res;
  if (FitCheck c = measure_experiments(experiments, o, res.points); !c.ok()) return timer.finish(res, c);
  PointRefs loops, mags;  // into res.points, which no longer grows
  for (auto& p : res.points) {
    if (p.used) (p.magnitude_experiment ? mags : loops).push_back(&p);
    p.area_fitted = p.used && !p.magnitude_experiment && !small_loop(p, o);
  }
  if (FitCheck c = fit_centre_line(loops, o, res); !c.ok()) return timer.finish(res, c);
  double x[2] = {0.0, 0.0};
  if (FitCheck c = seed_b_alpha(loops, res.hysteresis.a, o, x); !c.ok()) return timer.finish(res, c);
  if (FitCheck c = refine_b_alpha(loops, o, timer.clock(), x, res); !c.ok()) return timer.finish(res, c);
  if (mags.size() < 3) {
    return timer.finish(res, FitStatus::ok,
                        mags.empty() ? "no magnitude experiments: stage (k, c) not identified"
                                     : "fewer than 3 magnitude experiments: stage (k, c) not identified");
  }
  const double fs = experiments.front().sample_rate_Hz;
  if (FitCheck c = fit_stage(mags, fs, o, timer.clock(), res); !c.ok()) return timer.finish(res, c);
  res.stage_identified = true;
  if (!o.correct_lag) {
    res.lag_note = "areas not corrected for the lag (correct_lag = false)";
  } else {
    correct_for_lag(loops, mags, fs, o, res);
    // Once more on the corrected areas, from where the first pass ended. The lag itself stays as
    // the first pass's stage and loop gave it: their refit moves it by second-order amounts.
    if (res.lag_identified) {
      if (FitCheck c = refine_b_alpha(loops, o, timer.clock(), x, res); !c.ok()) return timer.finish(res, c);
      if (FitCheck c = fit_stage(mags, fs, o, timer.clock(), res); !c.ok()) return timer.finish(res, c);
    }
  }
  return timer.finish(res, FitStatus::ok);
}

}  // namespace hystloop
