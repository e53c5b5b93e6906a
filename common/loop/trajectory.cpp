#include "loop/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "core/errors.hpp"

namespace hystloop {

namespace {

constexpr double kPi = std::numbers::pi;

// The rounded triangle of unit amplitude at x, the fraction of the period in [0, 1), for a corner
// that lasts `corner` periods (0 < corner < 1/2). Corners are centred on the peaks at x = 1/4 and
// x = 3/4; within one, at u periods from its peak, the position is 1 - (2 v c / pi) sin^2(pi u / (2 c))
// (the integral of the half-cosine velocity, with 1 - cos written as 2 sin^2 to keep its digits
// near the peak).
double rounded_triangle(double x, double corner) noexcept {
  const double half = 0.5 * corner;
  const double v = 1.0 / (0.25 - half + corner / kPi);  // slope [1 / period]: the straight parts meet the corners
  const double depth = 2.0 * v * corner / kPi;
  auto turn = [&](double u) {
    const double s = std::sin(kPi * u / (2.0 * corner));
    return depth * s * s;
  };
  if (x < 0.25 - half) return v * x;
  if (x <= 0.25 + half) return 1.0 - turn(x - 0.25);
  if (x < 0.75 - half) return v * (0.5 - x);
  if (x <= 0.75 + half) return turn(x - 0.75) - 1.0;
  return v * (x - 1.0);
}

}  // namespace

std::string_view to_string(TrajectoryShape shape) noexcept {
  const auto i = static_cast<std::size_t>(shape);
  return i < kTrajectoryShapeNames.size() ? kTrajectoryShapeNames[i] : "unknown";
}

std::optional<TrajectoryShape> trajectory_shape_named(std::string_view name) noexcept {
  for (std::size_t i = 0; i < kTrajectoryShapeNames.size(); ++i) {
    if (kTrajectoryShapeNames[i] == name) return static_cast<TrajectoryShape>(i);
  }
  return std::nullopt;
}

std::string trajectory_shape_choices() { return choice_list(kTrajectoryShapeNames); }

void TrajectorySpec::validate() const {
  require_finite("trajectory.amplitude_m", amplitude_m);
  require_finite("trajectory.offset_m", offset_m);
  require_finite("trajectory.phase_rad", phase_rad);
  require_finite("trajectory.start_s", start_s);
  require_non_negative("trajectory.blend_s", blend_s);
  require_finite("trajectory.hold_m", hold_m);
  switch (shape) {
    case TrajectoryShape::kHold: break;
    case TrajectoryShape::kSine:
    case TrajectoryShape::kCosine: require_positive("trajectory.frequency_hz", frequency_hz); break;
    case TrajectoryShape::kTriangle:
      require_positive("trajectory.frequency_hz", frequency_hz);
      require_non_negative("trajectory.corner_s", corner_s);
      if (!(corner_s < 0.5 / frequency_hz)) {
        throw ParameterError("trajectory.corner_s",
                             "must be below half the period (" + std::to_string(0.5 / frequency_hz) + " s at " +
                                 std::to_string(frequency_hz) + " Hz; got " + std::to_string(corner_s) + " s)");
      }
      break;
    case TrajectoryShape::kPoints:
      if (n_points == 0 || n_points > kMaxPoints) {
        throw ParameterError("trajectory.n_points", "must be in [1, " + std::to_string(kMaxPoints) + "] (got " +
                                                        std::to_string(n_points) + ")");
      }
      for (std::size_t i = 0; i < n_points; ++i) {
        require_finite("trajectory.points_t_s", points_t_s[i]);
        require_finite("trajectory.points_y_m", points_y_m[i]);
        if (i > 0 && !(points_t_s[i] > points_t_s[i - 1])) {
          throw ParameterError("trajectory.points_t_s",
                               "times must increase strictly (index " + std::to_string(i) + ")");
        }
      }
      break;
    default: throw ParameterError("trajectory.shape", "unknown shape " + std::to_string(static_cast<int>(shape)));
  }
}

double evaluate_shape(const TrajectorySpec& spec, double tau_s) noexcept {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  const double phase = kTwoPi * spec.frequency_hz * tau_s + spec.phase_rad;
  switch (spec.shape) {
    case TrajectoryShape::kHold: return spec.offset_m;
    case TrajectoryShape::kSine: return spec.offset_m + spec.amplitude_m * std::sin(phase);
    case TrajectoryShape::kCosine: return spec.offset_m + spec.amplitude_m * std::cos(phase);
    case TrajectoryShape::kTriangle: {
      // Same phase convention as sine: starts at 0 rising, peak at a quarter period.
      const double x = phase / kTwoPi - std::floor(phase / kTwoPi);  // [0, 1)
      const double corner = spec.corner_s * spec.frequency_hz;       // [periods]
      if (corner > 0.0 && corner < 0.5) return spec.offset_m + spec.amplitude_m * rounded_triangle(x, corner);
      const double tri = x < 0.25 ? 4.0 * x : (x < 0.75 ? 2.0 - 4.0 * x : 4.0 * x - 4.0);
      return spec.offset_m + spec.amplitude_m * tri;
    }
    case TrajectoryShape::kPoints: {
      const std::size_t n = std::min(spec.n_points, TrajectorySpec::kMaxPoints);
      if (n == 0) return spec.offset_m;
      if (tau_s <= spec.points_t_s[0]) return spec.offset_m + spec.points_y_m[0];
      if (tau_s >= spec.points_t_s[n - 1]) return spec.offset_m + spec.points_y_m[n - 1];
      const auto* end = spec.points_t_s.data() + n;
      const auto* hi = std::upper_bound(spec.points_t_s.data(), end, tau_s);
      const std::size_t j = static_cast<std::size_t>(hi - spec.points_t_s.data());
      const double t0 = spec.points_t_s[j - 1], t1 = spec.points_t_s[j];
      const double w = (tau_s - t0) / (t1 - t0);
      return spec.offset_m + spec.points_y_m[j - 1] + w * (spec.points_y_m[j] - spec.points_y_m[j - 1]);
    }
  }
  return spec.offset_m;
}

namespace {

// The shape's curvature at tau: exact for sine and cosine; for the triangle by a central
// difference (the shapes are periodic, hence defined before tau = 0) with a step well inside a
// rounded corner.
double shape_curvature(const TrajectorySpec& spec, double tau_s) noexcept {
  if (spec.shape == TrajectoryShape::kSine || spec.shape == TrajectoryShape::kCosine) {
    const double w = 2.0 * std::numbers::pi * spec.frequency_hz;
    return -w * w * (evaluate_shape(spec, tau_s) - spec.offset_m);
  }
  double eps = 1e-3 / spec.frequency_hz;
  if (spec.shape == TrajectoryShape::kTriangle) eps = std::min(eps, spec.corner_s / 20.0);
  return (evaluate_shape(spec, tau_s + eps) - 2.0 * evaluate_shape(spec, tau_s) + evaluate_shape(spec, tau_s - eps)) /
         (eps * eps);
}

bool sharp_corners(const TrajectorySpec& spec) noexcept {
  return spec.shape == TrajectoryShape::kTriangle && !(spec.corner_s > 0.0);
}

}  // namespace

double first_extreme_s(const TrajectorySpec& spec) noexcept {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  if (!periodic(spec) || !(spec.frequency_hz > 0.0)) return 0.0;
  // The shape's phase (in periods) at tau = 0, and where its first peak or trough lies after it:
  // sine and triangle at a quarter and three quarters of a period, cosine at 0 and a half.
  const double at = spec.phase_rad / kTwoPi;
  const double first = spec.shape == TrajectoryShape::kCosine ? 0.0 : 0.25;
  double to = first - at;
  to -= 0.5 * std::floor(to / 0.5);              // [0, 0.5)
  if (to > 0.5 - 1e-12 || to < 1e-12) to = 0.0;  // already at an extreme (rounding)
  double tau = to / spec.frequency_hz;
  // Entered from the side it bends away from: a peak from below, a trough from above (otherwise
  // the approach would overshoot it and come back: an extra reversal). Else the next extreme.
  if (!sharp_corners(spec)) {
    const double y = evaluate_shape(spec, tau);
    if ((y - spec.hold_m) * shape_curvature(spec, tau) > 0.0) tau += 0.5 / spec.frequency_hz;
  } else if (spec.amplitude_m != 0.0) {
    const double y = evaluate_shape(spec, tau);
    const bool peak = evaluate_shape(spec, tau + 0.01 / spec.frequency_hz) < y;
    if ((peak && y < spec.hold_m) || (!peak && y > spec.hold_m)) tau += 0.5 / spec.frequency_hz;
  }
  return tau;
}

double evaluate(const TrajectorySpec& spec, double t_s) noexcept {
  const double tau = t_s - spec.start_s;
  // A periodic shape is entered at a peak or trough, where it is at rest: the approach ends
  // there, so a sine or triangle that starts at a zero crossing does not begin with a kink in
  // velocity (which the stage's inverse would turn into a voltage step) nor with an extra
  // reversal (which would start a new branch of a hysteresis model's memory).
  const double enter = first_extreme_s(spec);
  if (tau >= enter) return evaluate_shape(spec, tau);
  const double approach = spec.blend_s + enter;
  if (approach <= 0.0) return evaluate_shape(spec, 0.0);
  const double into = tau + spec.blend_s;  // time since the approach began
  if (into <= 0.0) return spec.hold_m;
  const double y_enter = evaluate_shape(spec, enter);
  const double delta = y_enter - spec.hold_m;
  if (!periodic(spec)) {  // a raised cosine from hold_m to the shape's first value
    const double w = 0.5 - 0.5 * std::cos(std::numbers::pi * into / approach);
    return spec.hold_m + w * delta;
  }
  // A quintic from rest at hold_m that arrives at rest with the shape's own curvature a_e (a step
  // in acceleration would be a step of the stage inverse's input):
  //   y = hold + delta (10 s^3 - 15 s^4 + 6 s^5 + c s^3 (1 - s)^2 / 2),   c = a_e L^2 / delta,
  // monotone for -20 <= c <= 0 (entered from the side the shape bends away from, c <= 0). A long
  // approach to a fast sine would need c < -20: it then holds longer and moves over the last
  // L = sqrt(20 |delta| / |a_e|) only (0.7 of a period for delta of the amplitude, slower than the
  // sine itself). A triangle is entered in the middle of a corner, whose curvature v pi / tau is
  // far above its mean: matching it would make the approach a sprint; it takes the step in
  // acceleration instead (v pi / (tau k) of stage input: a fraction of a volt at the corner,
  // where the voltage is at rest).
  double length = approach, c = 0.0;
  if (spec.shape != TrajectoryShape::kTriangle && delta != 0.0) {
    const double a_enter = shape_curvature(spec, enter);
    c = std::min(0.0, a_enter * approach * approach / delta);
    if (c < -20.0) {
      length = std::sqrt(20.0 * std::abs(delta) / std::abs(a_enter));
      c = -20.0;
    }
  }
  const double s = (into - (approach - length)) / length;
  if (s <= 0.0) return spec.hold_m;
  const double s3 = s * s * s;
  return spec.hold_m + delta * (s3 * (10.0 - 15.0 * s + 6.0 * s * s) + 0.5 * c * s3 * (1.0 - s) * (1.0 - s));
}

bool periodic(const TrajectorySpec& spec) noexcept {
  return spec.shape == TrajectoryShape::kSine || spec.shape == TrajectoryShape::kCosine ||
         spec.shape == TrajectoryShape::kTriangle;
}

std::optional<std::int64_t> period_ticks(const TrajectorySpec& spec, double dt_s) noexcept {
  if (!periodic(spec) || !(dt_s > 0.0) || !std::isfinite(dt_s) || !(spec.frequency_hz > 0.0)) return std::nullopt;
  const double ticks = 1.0 / (spec.frequency_hz * dt_s);
  constexpr double kMaxTicks = 9.0e15;  // below 2^53: every whole number is exact
  if (!(ticks >= 0.5) || !(ticks <= kMaxTicks)) return std::nullopt;
  const double whole = std::round(ticks);
  if (std::abs(ticks - whole) > 1e-9 * ticks) return std::nullopt;
  return static_cast<std::int64_t>(whole);
}

double triangle_slope_m_per_s(const TrajectorySpec& spec) noexcept {
  if (spec.shape != TrajectoryShape::kTriangle) return 0.0;
  const double period_s = 1.0 / spec.frequency_hz;
  const double corner_s = spec.corner_s > 0.0 ? spec.corner_s : 0.0;
  return 2.0 * spec.amplitude_m / (0.5 * period_s - corner_s + 2.0 * corner_s / kPi);
}

ShapePeaks peak_derivatives(const TrajectorySpec& spec) noexcept {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  ShapePeaks p;
  switch (spec.shape) {
    case TrajectoryShape::kHold: break;
    case TrajectoryShape::kSine:
    case TrajectoryShape::kCosine: {
      const double w = 2.0 * kPi * spec.frequency_hz;
      p.velocity_m_per_s = w * std::abs(spec.amplitude_m);
      p.acceleration_m_per_s2 = w * p.velocity_m_per_s;
      p.jerk_m_per_s3 = w * p.acceleration_m_per_s2;
      break;
    }
    case TrajectoryShape::kTriangle: {
      const double v = std::abs(triangle_slope_m_per_s(spec));
      p.velocity_m_per_s = v;
      if (v == 0.0) break;
      p.acceleration_m_per_s2 = spec.corner_s > 0.0 ? v * kPi / spec.corner_s : kInf;
      p.jerk_m_per_s3 = spec.corner_s > 0.0 ? v * kPi * kPi / (spec.corner_s * spec.corner_s) : kInf;
      break;
    }
    case TrajectoryShape::kPoints: {
      const std::size_t n = std::min(spec.n_points, TrajectorySpec::kMaxPoints);
      for (std::size_t i = 1; i < n; ++i) {
        const double slope =
            (spec.points_y_m[i] - spec.points_y_m[i - 1]) / (spec.points_t_s[i] - spec.points_t_s[i - 1]);
        p.velocity_m_per_s = std::max(p.velocity_m_per_s, std::abs(slope));
      }
      // The last point is held: any slope other than 0 ends in a kink.
      if (p.velocity_m_per_s > 0.0) p.acceleration_m_per_s2 = p.jerk_m_per_s3 = kInf;
      break;
    }
  }
  return p;
}

TrajectorySpec mem_paper_reference(double start_s, double blend_s, double hold_m) {
  TrajectorySpec s;
  s.shape = TrajectoryShape::kCosine;
  s.amplitude_m = -1.6e-6;
  s.frequency_hz = 1.0;
  s.start_s = start_s;
  s.blend_s = blend_s;
  s.hold_m = hold_m;
  return s;
}

}  // namespace hystloop
