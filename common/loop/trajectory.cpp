#include "loop/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "core/errors.hpp"

namespace hystloop {

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
    case TrajectoryShape::kCosine:
    case TrajectoryShape::kTriangle: require_positive("trajectory.frequency_hz", frequency_hz); break;
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

double evaluate(const TrajectorySpec& spec, double t_s) noexcept {
  const double tau = t_s - spec.start_s;
  if (tau >= 0.0) return evaluate_shape(spec, tau);
  if (spec.blend_s <= 0.0) return evaluate_shape(spec, 0.0);
  // Approach: hold, then a raised cosine from hold_m to the shape's first value.
  const double into = tau + spec.blend_s;  // time since the approach began
  if (into <= 0.0) return spec.hold_m;
  const double w = 0.5 - 0.5 * std::cos(std::numbers::pi * into / spec.blend_s);
  return spec.hold_m + w * (evaluate_shape(spec, 0.0) - spec.hold_m);
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
