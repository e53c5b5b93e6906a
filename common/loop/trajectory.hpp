#pragma once
// The reference the stage must follow, evaluated at a tick's time. Plain data plus a
// pure evaluate(t): the compensator evaluates it per tick, tests evaluate it directly.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace hystloop {

enum class TrajectoryShape : std::int8_t { kHold = 0, kSine = 1, kCosine = 2, kTriangle = 3, kPoints = 4 };

// The shapes' names, in the enum's order: the one table behind config (trajectory.shape), ctl's
// --shape, describe() and the report. trajectory_t's shape constants are the same numbers
// (lcm/trajectory_shape.hpp maps and checks them).
inline constexpr std::array<std::string_view, 5> kTrajectoryShapeNames{"hold", "sine", "cosine", "triangle", "points"};
std::string_view to_string(TrajectoryShape shape) noexcept;  // "unknown" outside the enum
std::optional<TrajectoryShape> trajectory_shape_named(std::string_view name) noexcept;
// "hold, sine, cosine, triangle or points", for a refusal that lists what is accepted.
std::string trajectory_shape_choices();

// y_ref(t) for t >= start_s. Before start_s the reference approaches the shape's first value
// from hold_m along a raised cosine over blend_s (it holds hold_m before that), so switching
// trajectories never asks the stage for a step (which would ring its 1.7 kHz mode), and the
// approach is monotone: a hysteresis inverse sees one clean branch into the shape, not an
// extra reversal that would offset the loop of a model without memory wipe-out (MEM).
//
// The triangle's corners are rounded over corner_s: around each peak the velocity turns from
// +v to -v along a half cosine, v(t) = v cos(pi t / corner_s), so the acceleration is
// continuous and the jerk bounded. The stage's inverse differentiates the reference twice and
// more, and a sharp corner would ask it for an unbounded voltage rate. The peaks stay at
// +-amplitude, the period at 1 / frequency_hz and the phase as today's triangle's (0 rising at
// t = 0, the peak a quarter period later, as sine); the straight parts have slope +-v with
//   2 A = v (T/2 - corner_s) + 2 v corner_s / pi,   i.e.   v = 2 A / (T/2 - corner_s + 2 corner_s / pi),
// peak acceleration v pi / corner_s and peak jerk v pi^2 / corner_s^2. corner_s = 0 is the sharp
// triangle, bit for bit.
struct TrajectorySpec {
  static constexpr std::size_t kMaxPoints = 256;

  TrajectoryShape shape = TrajectoryShape::kHold;
  double amplitude_m = 0.0;   // peak, metres
  double offset_m = 0.0;      // added to the shape, metres
  double frequency_hz = 1.0;  // for sine/cosine/triangle
  double phase_rad = 0.0;
  double corner_s = 0.0;  // triangle: duration of each rounded corner [s], in [0, T/2); 0 = sharp
  double start_s = 0.0;   // loop time at which the shape's t = 0
  double blend_s = 0.0;   // approach from hold_m, ending at start_s [s] (0 = none)
  double hold_m = 0.0;    // where the reference was before this trajectory
  // kPoints: piecewise-linear through (t, y), t relative to start_s and increasing;
  // held at the last point afterwards.
  std::size_t n_points = 0;
  std::array<double, kMaxPoints> points_t_s{};
  std::array<double, kMaxPoints> points_y_m{};
  // What the sender wants when the feedforward would leave the actuator's range or slew limit:
  // false = refuse the trajectory, true = shape it to feasibility (trajectory_t.if_infeasible).
  // The shape itself never reads it.
  bool shape_if_infeasible = false;

  // Throws ParameterError naming the field when a value is unusable.
  void validate() const;
};

// The shape alone (no blend), at time tau = t - start_s.
double evaluate_shape(const TrajectorySpec& spec, double tau_s) noexcept;

// The reference at loop time t, including the approach. Allocation- and throw-free.
double evaluate(const TrajectorySpec& spec, double t_s) noexcept;

// Where a periodic shape is entered, relative to start_s [s]: its first peak or trough at or
// after tau = 0 (0 for a cosine of phase 0, a quarter period for a sine or triangle of phase 0).
// The approach from hold_m ends there, monotone and at rest; the shape is exact from there on.
// 0 for the other shapes.
double first_extreme_s(const TrajectorySpec& spec) noexcept;

// Sine, cosine and triangle repeat with period 1 / frequency_hz; hold and points do not.
bool periodic(const TrajectorySpec& spec) noexcept;

// The period in ticks of dt_s when it is a whole number of them (within 1e-9 relative): 10 Hz at
// 1e-4 s is 1000 ticks; 30 Hz (333.33 ticks) has none. nullopt too for a shape that is not
// periodic and for a dt_s that is not finite and > 0.
std::optional<std::int64_t> period_ticks(const TrajectorySpec& spec, double dt_s) noexcept;

// The triangle's slope on its straight parts [m/s], signed as amplitude_m (the closed form above;
// 4 A f for the sharp triangle). 0 for the other shapes.
double triangle_slope_m_per_s(const TrajectorySpec& spec) noexcept;

// Peak magnitudes of the shape's derivatives (the shape alone, not the approach from hold_m).
// Sine/cosine: (2 pi f)^n |A|; triangle: v, v pi / corner_s, v pi^2 / corner_s^2 (infinite for a
// sharp corner); hold: 0; points: the steepest segment's slope, and infinite acceleration and
// jerk where the slope changes anywhere (a kink).
struct ShapePeaks {
  double velocity_m_per_s = 0.0;
  double acceleration_m_per_s2 = 0.0;
  double jerk_m_per_s3 = 0.0;
};
ShapePeaks peak_derivatives(const TrajectorySpec& spec) noexcept;

// The MEM paper's tracking experiment, eq. (24): y_d(t) = -1.6 um * cos(2 pi t).
TrajectorySpec mem_paper_reference(double start_s, double blend_s = 0.0, double hold_m = 0.0);

}  // namespace hystloop
