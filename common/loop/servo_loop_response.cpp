#include "loop/servo_loop_response.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <Eigen/Eigenvalues>

#include "core/errors.hpp"
#include "loop/notch_filter.hpp"

namespace hystloop {
namespace {

using Poly = std::vector<double>;  // in z^-1, lowest power first
using Complex = std::complex<double>;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Poly multiply(const Poly& a, const Poly& b) {
  Poly out(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) out[i + j] += a[i] * b[j];
  return out;
}

Poly add(Poly a, const Poly& b) {
  if (a.size() < b.size()) a.resize(b.size(), 0.0);
  for (std::size_t i = 0; i < b.size(); ++i) a[i] += b[i];
  return a;
}

Poly scale(Poly a, double s) {
  for (double& x : a) x *= s;
  return a;
}

Complex evaluate(const Poly& p, Complex z_inv) {
  Complex out = 0.0, power = 1.0;
  for (const double c : p) {
    out += c * power;
    power *= z_inv;
  }
  return out;
}

// The stage's ZOH transfer function from its first Markov parameters: h_n = C Phi^(n-1) Gamma
// is the response to one tick of unit input, and h_(n+2) = tr(Phi) h_(n+1) - det(Phi) h_n.
void stage_zoh(const ServoLoopModel& m, Poly& num, Poly& den) {
  if (m.linear) {
    // G(z) maps the voltage held over tick k to the position at its end; the servo uses that
    // position at tick k + 1: one more z^-1, as h_0 below.
    const DiscreteLinearStage d = discretise(*m.linear, m.dt_s);
    num.assign(1, 0.0);
    num.insert(num.end(), d.numerator.begin(), d.numerator.end());
    den.assign(d.denominator.begin(), d.denominator.end());
    return;
  }
  SecondOrderStage stage(m.stage);
  double h[4];
  for (int i = 0; i < 4; ++i) h[i] = stage.step(i == 0 ? 1.0 : 0.0, m.dt_s);
  const double det_h = h[1] * h[1] - h[0] * h[2];
  const double tr = (h[2] * h[1] - h[3] * h[0]) / det_h;
  const double det = (h[2] * h[2] - h[1] * h[3]) / det_h;
  num = {0.0, h[0], h[1] - tr * h[0]};
  den = {1.0, -tr, det};
}

// Where f(lo) and f(hi) differ in sign, the zero between them (bisection on a log axis).
template <class F>
double bisect(F&& f, double lo, double hi) {
  const bool lo_sign = f(lo) > 0.0;
  for (int i = 0; i < 60; ++i) {
    const double mid = std::sqrt(lo * hi);
    if ((f(mid) > 0.0) == lo_sign) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return std::sqrt(lo * hi);
}

}  // namespace

void ServoLoopModel::validate() const {
  require_positive("loop.dt_s", dt_s);
  if (linear) {
    linear->validate(dt_s);
  } else {
    stage.validate();
  }
  require_positive("loop.slope_ratio", slope_ratio);
  require_in_range("loop.extra_delay_ticks", extra_delay_ticks, 0, 100);
}

ServoLoopResponse::ServoLoopResponse(const FeedbackGains& gains_in, const ServoLoopModel& model) : dt_s_(model.dt_s) {
  model.validate();
  FeedbackGains g = gains_in;
  g.tick_rate_hz = 1.0 / model.dt_s;
  g.validate();
  const double T = model.dt_s;
  // C(z) = kp + ki T / (1 - z^-1) + kd a / T (1 - z^-1) / (1 - (1 - a) z^-1), over the nominal gain.
  Poly c_num = add(scale({1.0, -1.0}, g.kp), {g.ki * T});
  Poly c_den = {1.0, -1.0};
  if (g.kd > 0.0) {
    const double a = T / (T + 1.0 / (2.0 * std::numbers::pi * g.d_filter_hz));
    const Poly d_den = {1.0, -(1.0 - a)};
    c_num = add(multiply(c_num, d_den), scale(multiply({1.0, -1.0}, {1.0, -1.0}), g.kd * a / T));
    c_den = multiply(c_den, d_den);
  }
  Poly p_num, p_den;
  stage_zoh(model, p_num, p_den);
  num_ = scale(multiply(c_num, p_num), model.slope_ratio);
  den_ = multiply(c_den, p_den);
  for (std::size_t i = 0; i < kServoNotches; ++i) {
    const ServoNotch notch = g.notch(i);
    if (!notch.on()) continue;
    const BiquadCoefficients n = design_notch(notch.hz, notch.q, g.tick_rate_hz);
    num_ = multiply(num_, {n.b0, n.b1, n.b2});
    den_ = multiply(den_, {1.0, n.a1, n.a2});
  }
  Poly delay(static_cast<std::size_t>(model.extra_delay_ticks) + 1, 0.0);
  delay.back() = 1.0;
  num_ = multiply(num_, delay);
}

Complex ServoLoopResponse::loop_gain(double f_hz) const {
  const Complex z_inv = std::polar(1.0, -2.0 * std::numbers::pi * f_hz * dt_s_);
  return evaluate(num_, z_inv) / evaluate(den_, z_inv);
}

double ServoLoopResponse::sensitivity(double f_hz) const { return 1.0 / std::abs(1.0 + loop_gain(f_hz)); }

std::vector<Complex> ServoLoopResponse::closed_loop_poles() const {
  // 1 + L = 0  <=>  den + num = 0; in z: sum c_i z^(n - i), its roots from the companion matrix.
  Poly c = add(den_, num_);
  while (c.size() > 1 && c.back() == 0.0) c.pop_back();
  const auto n = static_cast<Eigen::Index>(c.size()) - 1;
  if (n < 1) return {};
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 0; i < n; ++i) companion(0, i) = -c[static_cast<std::size_t>(i) + 1] / c[0];
  for (Eigen::Index i = 1; i < n; ++i) companion(i, i - 1) = 1.0;
  const Eigen::EigenSolver<Eigen::MatrixXd> solver(companion, false);
  std::vector<Complex> poles;
  for (Eigen::Index i = 0; i < n; ++i) poles.push_back(solver.eigenvalues()(i));
  return poles;
}

bool ServoLoopResponse::stable() const {
  const std::vector<Complex> poles = closed_loop_poles();
  return std::all_of(poles.begin(), poles.end(), [](const Complex& p) { return std::abs(p) < 1.0; });
}

LoopMargins ServoLoopResponse::margins() const {
  LoopMargins m;
  for (const Complex& p : closed_loop_poles()) m.max_pole_radius = std::max(m.max_pole_radius, std::abs(p));
  m.stable = m.max_pole_radius < 1.0;
  m.gain_margin_dB = kInf;
  m.gain_margin_hz = kNaN;
  m.phase_margin_deg = kInf;
  m.crossover_hz = kNaN;
  const double nyquist = 0.5 / dt_s_;
  const auto magnitude = [&](double f) { return std::abs(loop_gain(f)) - 1.0; };
  const auto imag = [&](double f) { return loop_gain(f).imag(); };
  const auto take_gain_margin = [&](double f) {
    const Complex l = loop_gain(f);
    if (l.real() >= 0.0) return;
    const double gm = -20.0 * std::log10(std::abs(l));
    if (gm < m.gain_margin_dB) m.gain_margin_dB = gm, m.gain_margin_hz = f;
  };
  // A log grid from 0.01 Hz to just below Nyquist, every crossing refined by bisection.
  constexpr int kPoints = 20000;
  const double f_lo = 0.01, f_hi = nyquist * (1.0 - 1e-9);
  double prev_f = f_lo;
  for (int i = 0; i <= kPoints; ++i) {
    const double f = f_lo * std::pow(f_hi / f_lo, static_cast<double>(i) / kPoints);
    const double s = sensitivity(f);
    if (s > m.sensitivity_peak) m.sensitivity_peak = s, m.sensitivity_peak_hz = f;
    if (i > 0) {
      if ((magnitude(prev_f) > 0.0) != (magnitude(f) > 0.0)) {
        const double fc = bisect(magnitude, prev_f, f);
        const double pm = 180.0 - std::abs(std::arg(loop_gain(fc))) * 180.0 / std::numbers::pi;
        m.phase_margin_deg = std::min(m.phase_margin_deg, pm);
        if (std::isnan(m.crossover_hz)) m.crossover_hz = fc;
      }
      if ((imag(prev_f) > 0.0) != (imag(f) > 0.0)) take_gain_margin(bisect(imag, prev_f, f));
    }
    prev_f = f;
  }
  take_gain_margin(nyquist);  // L is real there: a crossing when it is negative
  return m;
}

double largest_stable_ki(FeedbackGains gains, const ServoLoopModel& model, double ki_max_per_s, double tol_per_s) {
  require_positive("ki_max_per_s", ki_max_per_s);
  require_positive("tol_per_s", tol_per_s);
  const auto stable = [&](double ki) {
    gains.ki = ki;
    return ServoLoopResponse(gains, model).stable();
  };
  double lo = std::min(tol_per_s, ki_max_per_s);
  if (!stable(lo)) return 0.0;
  for (double hi = lo * 1.02;; hi *= 1.02) {
    hi = std::min(hi, ki_max_per_s);
    if (!stable(hi)) {
      while (hi - lo > tol_per_s) {
        const double mid = 0.5 * (lo + hi);
        (stable(mid) ? lo : hi) = mid;
      }
      return lo;
    }
    if (hi >= ki_max_per_s) return ki_max_per_s;
    lo = hi;
  }
}

}  // namespace hystloop
