#include "loop/feasibility.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "core/errors.hpp"

namespace hystloop {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();

void require_corner(double frequency_hz, double corner_s) {
  require_non_negative("corner_s", corner_s);
  if (!(corner_s < 0.5 / frequency_hz)) {
    throw ParameterError("corner_s", "must be below half the period (" + std::to_string(0.5 / frequency_hz) +
                                         " s; got " + std::to_string(corner_s) + " s)");
  }
}

// Headroom of the usable range around the voltage that holds the offset [V]; < 0 when the offset
// alone does not fit.
double headroom_V(const LinearPlant& plant, const FeedforwardLimits& limits, double offset_m) noexcept {
  const double centre_V = offset_m / plant.gain_m_per_V;
  return std::min(limits.usable_max_V() - centre_V, centre_V - limits.usable_min_V());
}

VoltageNeed symmetric_need(const LinearPlant& plant, double offset_m, double peak_m, double rate_m_per_s) noexcept {
  const double g = plant.gain_m_per_V;
  return {(offset_m - peak_m) / g, (offset_m + peak_m) / g, rate_m_per_s / g};
}

// The triangle's peaks per unit slope v: the rate factor max(1, hypot(...)) and W / v, with W
// written as |A| + v * (return value) (see the header).
struct TrianglePeaks {
  double rate_per_v = 1.0;  // |du/dt| g / v
  double excess_s = 0.0;    // (W - |A|) / v [s]
};

TrianglePeaks triangle_peaks(const LinearPlant& plant, double corner_s) noexcept {
  if (!plant.stage) return {};
  if (!(corner_s > 0.0)) return {kInf, kInf};
  const double k = plant.stage->k, c = plant.stage->c, tau = corner_s;
  TrianglePeaks p;
  p.rate_per_v = std::max(1.0, std::hypot(kPi * kPi / (k * tau * tau) - 1.0, c * kPi / (k * tau)));
  const double a = tau / kPi - kPi / (k * tau);
  const double b = c / k;
  p.excess_s = -tau / kPi + (a >= 0.0 ? std::hypot(a, b) : b);
  return p;
}

double triangle_slope(double amplitude_m, double frequency_hz, double corner_s) noexcept {
  return 2.0 * std::abs(amplitude_m) / (0.5 / frequency_hz - corner_s + 2.0 * corner_s / kPi);
}

// Bisection of a bracket [lo, hi] on which `feasible` goes from true at lo to false at hi (or the
// other way round, with lo_feasible false): returns the end on the feasible side, to rounding.
template <class F>
double bisect(double lo, double hi, bool lo_feasible, F&& feasible) {
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (!(mid > lo && mid < hi)) break;
    (feasible(mid) == lo_feasible ? lo : hi) = mid;
  }
  return lo_feasible ? lo : hi;
}

}  // namespace

void LinearPlant::validate() const {
  require_positive("plant.gain_m_per_V", gain_m_per_V);
  if (stage) {
    require_positive("plant.stage.k", stage->k);
    require_positive("plant.stage.c", stage->c);
  }
}

void FeedforwardLimits::validate() const {
  require_finite("limits.u_min_V", u_min_V);
  require_finite("limits.u_max_V", u_max_V);
  if (!(u_max_V > u_min_V)) {
    throw ParameterError("limits.u_max_V", "must be above limits.u_min_V (got " + std::to_string(u_max_V) +
                                               " <= " + std::to_string(u_min_V) + ")");
  }
  require_positive("limits.slew_V_per_s", slew_V_per_s);
  require_positive("limits.fraction", fraction);
  require_in_range("limits.fraction", fraction, 0.0, 1.0);
}

double FeedforwardLimits::usable_min_V() const noexcept {
  return 0.5 * (u_min_V + u_max_V) - fraction * 0.5 * (u_max_V - u_min_V);
}

double FeedforwardLimits::usable_max_V() const noexcept {
  return 0.5 * (u_min_V + u_max_V) + fraction * 0.5 * (u_max_V - u_min_V);
}

double FeedforwardLimits::usable_slew_V_per_s() const noexcept { return fraction * slew_V_per_s; }

const char* to_string(Limit limit) noexcept {
  switch (limit) {
    case Limit::kNone: return "none";
    case Limit::kRange: return "range";
    case Limit::kSlew: return "slew";
  }
  return "?";
}

Limit exceeded_limit(const VoltageNeed& need, const FeedforwardLimits& limits) noexcept {
  if (!(need.u_min_V >= limits.usable_min_V() && need.u_max_V <= limits.usable_max_V())) return Limit::kRange;
  if (!(need.rate_V_per_s <= limits.usable_slew_V_per_s())) return Limit::kSlew;
  return Limit::kNone;
}

double stage_inverse_gain(const LinearPlant& plant, double frequency_hz) noexcept {
  if (!plant.stage) return 1.0;
  const double w = 2.0 * kPi * frequency_hz;
  const double k = plant.stage->k;
  return std::hypot(k - w * w, plant.stage->c * w) / k;
}

VoltageNeed sine_need(const LinearPlant& plant, double amplitude_m, double frequency_hz, double offset_m) {
  plant.validate();
  require_positive("frequency_hz", frequency_hz);
  require_finite("amplitude_m", amplitude_m);
  require_finite("offset_m", offset_m);
  const double peak_m = std::abs(amplitude_m) * stage_inverse_gain(plant, frequency_hz);
  return symmetric_need(plant, offset_m, peak_m, 2.0 * kPi * frequency_hz * peak_m);
}

VoltageNeed triangle_need(const LinearPlant& plant, double amplitude_m, double frequency_hz, double corner_s,
                          double offset_m) {
  plant.validate();
  require_positive("frequency_hz", frequency_hz);
  require_corner(frequency_hz, corner_s);
  require_finite("amplitude_m", amplitude_m);
  require_finite("offset_m", offset_m);
  if (amplitude_m == 0.0) return symmetric_need(plant, offset_m, 0.0, 0.0);
  const double v = triangle_slope(amplitude_m, frequency_hz, corner_s);
  const TrianglePeaks p = triangle_peaks(plant, corner_s);
  return symmetric_need(plant, offset_m, std::abs(amplitude_m) + v * p.excess_s, v * p.rate_per_v);
}

VoltageNeed voltage_need(const LinearPlant& plant, const TrajectorySpec& spec) {
  spec.validate();
  plant.validate();
  switch (spec.shape) {
    case TrajectoryShape::kSine:
    case TrajectoryShape::kCosine: return sine_need(plant, spec.amplitude_m, spec.frequency_hz, spec.offset_m);
    case TrajectoryShape::kTriangle:
      return triangle_need(plant, spec.amplitude_m, spec.frequency_hz, spec.corner_s, spec.offset_m);
    case TrajectoryShape::kPoints: {
      const auto* y = spec.points_y_m.data();
      const auto [lo, hi] = std::minmax_element(y, y + spec.n_points);
      const double g = plant.gain_m_per_V;
      const ShapePeaks peaks = peak_derivatives(spec);
      const bool kinked = plant.stage && peaks.velocity_m_per_s > 0.0;
      if (kinked) return {-kInf, kInf, kInf};
      return {(spec.offset_m + *lo) / g, (spec.offset_m + *hi) / g, peaks.velocity_m_per_s / g};
    }
    case TrajectoryShape::kHold: break;
  }
  return symmetric_need(plant, spec.offset_m, 0.0, 0.0);
}

double largest_sine_amplitude_m(const LinearPlant& plant, const FeedforwardLimits& limits, double frequency_hz,
                                double offset_m) {
  plant.validate();
  limits.validate();
  require_positive("frequency_hz", frequency_hz);
  require_finite("offset_m", offset_m);
  const double headroom = headroom_V(plant, limits, offset_m);
  if (!(headroom >= 0.0)) return 0.0;
  const double w = 2.0 * kPi * frequency_hz;
  const double peak_V = std::min(headroom, limits.usable_slew_V_per_s() / w);
  return plant.gain_m_per_V * peak_V / stage_inverse_gain(plant, frequency_hz);
}

double highest_sine_frequency_hz(const LinearPlant& plant, const FeedforwardLimits& limits, double amplitude_m,
                                 double offset_m) {
  plant.validate();
  limits.validate();
  require_finite("amplitude_m", amplitude_m);
  require_finite("offset_m", offset_m);
  const double headroom = headroom_V(plant, limits, offset_m);
  if (!(headroom >= 0.0)) return 0.0;
  const double a = std::abs(amplitude_m);
  if (a == 0.0) return kInf;
  const double g = plant.gain_m_per_V;
  const double slew = limits.usable_slew_V_per_s();
  if (!plant.stage) return g * headroom >= a ? g * slew / (2.0 * kPi * a) : 0.0;

  const double k = plant.stage->k, c2 = plant.stage->c * plant.stage->c;
  // Range, with x = w^2: M^2 <= m^2 is x^2 - (2k - c^2) x + k^2 (1 - m^2) <= 0, which holds at x = 0
  // when m >= 1: the first crossing is the larger root.
  const double m = g * headroom / a;
  if (m < 1.0) return 0.0;
  const double p = 2.0 * k - c2;
  const double q = k * k * (1.0 - m * m);  // <= 0: the product of the roots
  const double root = std::sqrt(std::max(0.0, p * p - 4.0 * q));
  const double x_range = p >= 0.0 ? 0.5 * (p + root) : (root + p == 0.0 ? 0.0 : 2.0 * q / (p - root));

  // Rate: w |A| M / g <= S is r(x) = x ((k - x)^2 + c^2 x) - Q <= 0 with Q = (S g k / A)^2, r(0) = -Q;
  // the first crossing is the smallest positive root of the cubic. r rises to its local maximum at
  // x1 and falls to x2 (the roots of r' = 3x^2 - 4kx + k^2 + c^2) when k^2 > 3c^2, else rises
  // throughout; beyond x2 + 2k + Q^(1/3) it is positive.
  const double big_q = (slew * g * k / a) * (slew * g * k / a);
  auto r = [&](double x) { return x * ((k - x) * (k - x) + c2 * x) - big_q; };
  double lo = 0.0, hi = 2.0 * k + std::cbrt(big_q);
  const double disc = k * k - 3.0 * c2;
  if (disc > 0.0) {
    const double x1 = (2.0 * k - std::sqrt(disc)) / 3.0, x2 = (2.0 * k + std::sqrt(disc)) / 3.0;
    if (r(x1) >= 0.0) {
      hi = x1;
    } else {
      lo = x2;
      hi = x2 + 2.0 * k + std::cbrt(big_q);
    }
  }
  const double x_rate = bisect(lo, hi, true, [&](double x) { return r(x) <= 0.0; });
  return std::sqrt(std::min(x_range, x_rate)) / (2.0 * kPi);
}

double largest_triangle_amplitude_m(const LinearPlant& plant, const FeedforwardLimits& limits, double frequency_hz,
                                    double corner_s, double offset_m) {
  plant.validate();
  limits.validate();
  require_positive("frequency_hz", frequency_hz);
  require_corner(frequency_hz, corner_s);
  require_finite("offset_m", offset_m);
  const double headroom = headroom_V(plant, limits, offset_m);
  if (!(headroom >= 0.0)) return 0.0;
  const TrianglePeaks p = triangle_peaks(plant, corner_s);
  if (!std::isfinite(p.rate_per_v)) return 0.0;
  const double v_per_m = triangle_slope(1.0, frequency_hz, corner_s);  // slope of a unit triangle [1/s]
  const double g = plant.gain_m_per_V;
  const double by_range = g * headroom / (1.0 + v_per_m * p.excess_s);
  const double by_rate = g * limits.usable_slew_V_per_s() / (v_per_m * p.rate_per_v);
  return std::min(by_range, by_rate);
}

std::optional<double> shortest_triangle_corner_s(const LinearPlant& plant, const FeedforwardLimits& limits,
                                                 double amplitude_m, double frequency_hz, double offset_m) {
  plant.validate();
  limits.validate();
  require_positive("frequency_hz", frequency_hz);
  auto feasible = [&](double tau) {
    return fits(triangle_need(plant, amplitude_m, frequency_hz, tau, offset_m), limits);
  };
  if (feasible(0.0)) return 0.0;
  if (!plant.stage) return std::nullopt;  // the need only grows with the corner
  constexpr int kPerDecade = 300, kDecades = 9;
  const double half_period_s = 0.5 / frequency_hz;
  const double top_s = std::nextafter(half_period_s, 0.0);
  double below = 0.0;  // the last corner tried that did not fit (0: sharp, never fits with the stage)
  for (int i = -kPerDecade * kDecades; i <= 0; ++i) {
    const double tau = i == 0 ? top_s : half_period_s * std::pow(10.0, static_cast<double>(i) / kPerDecade);
    if (feasible(tau)) return bisect(below, tau, false, feasible);
    below = tau;
  }
  return std::nullopt;
}

}  // namespace hystloop
