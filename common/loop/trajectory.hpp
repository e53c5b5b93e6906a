#pragma once
// The reference the stage must follow, evaluated at a tick's time. Plain data plus a
// pure evaluate(t): the compensator evaluates it per tick, tests evaluate it directly.

#include <array>
#include <cstddef>
#include <cstdint>

namespace hystloop {

enum class TrajectoryShape : std::int8_t { kHold = 0, kSine = 1, kCosine = 2, kTriangle = 3, kPoints = 4 };

// y_ref(t) for t >= start_s. Before start_s the reference approaches the shape's first value
// from hold_m along a raised cosine over blend_s (it holds hold_m before that), so switching
// trajectories never asks the stage for a step (which would ring its 1.7 kHz mode), and the
// approach is monotone: a hysteresis inverse sees one clean branch into the shape, not an
// extra reversal that would offset the loop of a model without memory wipe-out (MEM).
struct TrajectorySpec {
  static constexpr std::size_t kMaxPoints = 256;

  TrajectoryShape shape = TrajectoryShape::kHold;
  double amplitude_m = 0.0;   // peak, metres
  double offset_m = 0.0;      // added to the shape, metres
  double frequency_hz = 1.0;  // for sine/cosine/triangle
  double phase_rad = 0.0;
  double start_s = 0.0;  // loop time at which the shape's t = 0
  double blend_s = 0.0;  // approach from hold_m, ending at start_s [s] (0 = none)
  double hold_m = 0.0;   // where the reference was before this trajectory
  // kPoints: piecewise-linear through (t, y), t relative to start_s and increasing;
  // held at the last point afterwards.
  std::size_t n_points = 0;
  std::array<double, kMaxPoints> points_t_s{};
  std::array<double, kMaxPoints> points_y_m{};

  // Throws ParameterError naming the field when a value is unusable.
  void validate() const;
};

// The shape alone (no blend), at time tau = t - start_s.
double evaluate_shape(const TrajectorySpec& spec, double tau_s) noexcept;

// The reference at loop time t, including the approach. Allocation- and throw-free.
double evaluate(const TrajectorySpec& spec, double t_s) noexcept;

// The MEM paper's tracking experiment, eq. (24): y_d(t) = -1.6 um * cos(2 pi t).
TrajectorySpec mem_paper_reference(double start_s, double blend_s = 0.0, double hold_m = 0.0);

}  // namespace hystloop
