#include "models/coleman_hodgdon_theory.hpp"

#include <cmath>
#include <limits>

namespace hystloop {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool in_domain(const ColemanHodgdonParams& p, double u_offset, double amplitude) noexcept {
  return std::isfinite(u_offset) && std::isfinite(amplitude) && amplitude > 0.0 &&
         std::abs(u_offset) + amplitude <= p.s_max;
}

// (1 - e^{-2x}) / (1 + e^{-2x}) = tanh(x), the recurring factor of the proof.
double t_of(const ColemanHodgdonParams& p, double amplitude) noexcept { return std::tanh(p.alpha * amplitude); }

// A - tanh(alpha A) / alpha without cancellation for small alpha A: (x - tanh x) / alpha.
double a_minus_tanh(double alpha, double amplitude) noexcept {
  const double x = alpha * amplitude;
  if (x < 1e-2) {
    const double x2 = x * x;
    return x * x2 * (1.0 / 3.0 - x2 * (2.0 / 15.0 - x2 * 17.0 / 315.0)) / alpha;
  }
  return (x - std::tanh(x)) / alpha;
}

// Ascending branch from the left turning point of a loop centred at the origin, in closed form
// (exponential solution of (10) with f = a s, g = b): w_up(s) for s in [-A, A].
double ascending_branch(const ColemanHodgdonParams& p, double amplitude, double s) noexcept {
  const double k = (p.b - p.a) / p.alpha;
  const double w_left = -p.a * amplitude - k * t_of(p, amplitude);
  return p.a * s + k + (w_left + p.a * amplitude - k) * std::exp(-p.alpha * (s + amplitude));
}

}  // namespace

double ch_left_turning_point(const ColemanHodgdonParams& p, double u_offset, double amplitude) noexcept {
  if (!in_domain(p, u_offset, amplitude)) return kNaN;
  return p.a * (u_offset - amplitude) - (p.b - p.a) / p.alpha * t_of(p, amplitude);
}

double ch_right_turning_point(const ColemanHodgdonParams& p, double u_offset, double amplitude) noexcept {
  if (!in_domain(p, u_offset, amplitude)) return kNaN;
  return p.a * (u_offset + amplitude) + (p.b - p.a) / p.alpha * t_of(p, amplitude);
}

double ch_slope(const ColemanHodgdonParams& p, double amplitude) noexcept {
  if (!in_domain(p, 0.0, amplitude)) return kNaN;
  return p.a + (p.b - p.a) / p.alpha * t_of(p, amplitude) / amplitude;
}

double ch_horizontal_aperture(const ColemanHodgdonParams& p, double amplitude) noexcept {
  if (!in_domain(p, 0.0, amplitude)) return kNaN;
  const double e = std::exp(-p.alpha * amplitude);
  const double m = -std::expm1(-p.alpha * amplitude);  // 1 - e^{-alpha A}
  return 2.0 * (p.a - p.b) / p.alpha * m * m / (p.a * m * m + 2.0 * p.b * e);
}

double ch_horizontal_aperture_exact(const ColemanHodgdonParams& p, double amplitude) noexcept {
  if (!in_domain(p, 0.0, amplitude)) return kNaN;
  // The loop is point symmetric about its centre, so delta = 2 s* with w_up(s*) = 0, s* in [0, A]
  // (w_up(0) = -eta/2 <= 0 <= w_up(A)). w_up is increasing: bisection to machine precision.
  double lo = 0.0;
  double hi = amplitude;
  for (int i = 0; i < 200 && hi - lo > 1e-15 * amplitude; ++i) {
    const double mid = 0.5 * (lo + hi);
    (ascending_branch(p, amplitude, mid) < 0.0 ? lo : hi) = mid;
  }
  return lo + hi;
}

double ch_vertical_aperture(const ColemanHodgdonParams& p, double amplitude) noexcept {
  if (!in_domain(p, 0.0, amplitude)) return kNaN;
  const double m = -std::expm1(-p.alpha * amplitude);
  return 2.0 * (p.a - p.b) / p.alpha * m * m / (1.0 + std::exp(-2.0 * p.alpha * amplitude));
}

double ch_area(const ColemanHodgdonParams& p, double amplitude) noexcept {
  if (!in_domain(p, 0.0, amplitude)) return kNaN;
  return 4.0 * (p.a - p.b) / p.alpha * a_minus_tanh(p.alpha, amplitude);
}

double ch_slope_small(const ColemanHodgdonParams& p) noexcept { return p.b; }

double ch_horizontal_aperture_small(const ColemanHodgdonParams& p, double amplitude) noexcept {
  if (!in_domain(p, 0.0, amplitude)) return kNaN;
  return p.alpha * (p.a / p.b - 1.0) * amplitude * amplitude;
}

double ch_vertical_aperture_small(const ColemanHodgdonParams& p, double amplitude) noexcept {
  if (!in_domain(p, 0.0, amplitude)) return kNaN;
  return p.alpha * (p.a - p.b) * amplitude * amplitude;
}

double ch_area_small(const ColemanHodgdonParams& p, double amplitude) noexcept {
  if (!in_domain(p, 0.0, amplitude)) return kNaN;
  return 4.0 / 3.0 * (p.a - p.b) * p.alpha * amplitude * amplitude * amplitude;
}

namespace {
// The loop of Theorem 3: turning points and centre in closed form, the shape (slope, delta, eta,
// area) from the flavour asked for.
LoopFeatures theorem3_loop(const ColemanHodgdonParams& p, double u_offset, double amplitude, double slope, double delta,
                           double eta, double area) noexcept {
  return {.u_min = u_offset - amplitude,
          .u_max = u_offset + amplitude,
          .y_left = ch_left_turning_point(p, u_offset, amplitude),
          .y_right = ch_right_turning_point(p, u_offset, amplitude),
          .u_centre = u_offset,
          .y_centre = in_domain(p, u_offset, amplitude) ? p.a * u_offset : kNaN,
          .slope = slope,
          .delta = delta,
          .eta = eta,
          .area = area};
}
}  // namespace

LoopFeatures theorem3_features(const ColemanHodgdonParams& p, double u_offset, double amplitude) noexcept {
  return theorem3_loop(p, u_offset, amplitude, ch_slope(p, amplitude), ch_horizontal_aperture(p, amplitude),
                       ch_vertical_aperture(p, amplitude), ch_area(p, amplitude));
}

LoopFeatures theorem3_small_amplitude(const ColemanHodgdonParams& p, double u_offset, double amplitude) noexcept {
  const double slope = in_domain(p, u_offset, amplitude) ? ch_slope_small(p) : kNaN;
  return theorem3_loop(p, u_offset, amplitude, slope, ch_horizontal_aperture_small(p, amplitude),
                       ch_vertical_aperture_small(p, amplitude), ch_area_small(p, amplitude));
}

LoopFeatures exact_loop_features(const ColemanHodgdonParams& p, double u_offset, double amplitude) noexcept {
  return theorem3_loop(p, u_offset, amplitude, ch_slope(p, amplitude), ch_horizontal_aperture_exact(p, amplitude),
                       ch_vertical_aperture(p, amplitude), ch_area(p, amplitude));
}

double stage_magnitude(const SecondOrderStageParams& p, double omega) noexcept {
  const double re = p.k - omega * omega;
  const double im = p.c * omega;
  return p.k / std::hypot(re, im);
}

double banning_peak_to_peak(const ColemanHodgdonParams& p, double magnitude, double amplitude) noexcept {
  const double x = p.alpha * amplitude * magnitude;
  return 2.0 * p.a * magnitude * amplitude + 2.0 * (p.b - p.a) / p.alpha * std::tanh(x);
}

double magnitude_from_peak_to_peak(double peak_to_peak, double b, double amplitude) noexcept {
  return peak_to_peak / (2.0 * b * amplitude);
}

}  // namespace hystloop
