#pragma once
// Multi-axis scan paths for an XY(Z) stage: a raster (a fast axis going back and forth, a slow axis
// stepping or ramping across) and a Lissajous figure (each axis a sine of its own frequency). Plain
// data plus a pure evaluate(t) per tick, as trajectory.hpp for one axis; the per-axis shapes are
// trajectory.hpp's (the fast axis is its rounded triangle, a Lissajous axis its sine) and the
// feasibility check is feasibility.hpp's, per axis.
//
// Raster geometry (tau = t - start_s, L = line_rate_hz, T = lines / L):
//   - line k (0-based) is tau in [k/L, (k+1)/L): the fast axis goes from one end to the other,
//     from centre - width/2 to centre + width/2 for even k and back for odd k. Its reference is the
//     rounded triangle of amplitude width/2 and frequency L/2 entered at its trough, so the line
//     boundaries k/L are the corners' centres (where the fast axis is at rest at an end) and the
//     straight parts are [k/L + corner_s/2, (k+1)/L - corner_s/2].
//   - steps: on line k's straight part the slow axis is at centre - height/2 + k height/(lines-1);
//     it moves by one line spacing within the corner centred on k/L. It moves along a raised cosine
//     in velocity (v ~ 1 - cos, a cycloid in position), so that, like the fast axis's corners, its
//     acceleration is continuous: the stage's inverse differentiates the reference twice, and a
//     step in acceleration would be a step of its voltage. Needs corner_s > 0. Its peak speed,
//     2 h / c for a spacing h = height / (lines - 1) in a corner of c, overtakes the fast axis's
//     when the lines are few and the corners short (8 lines over 2 um in 1 ms corners: 5.7e-4 m/s);
//     check_raster_feasible checks it.
//   - ramp: the slow axis rises at one constant slope from centre - height/2 at tau = 0 to
//     centre + height/2 at tau = T, across every line's straight part and corner; it starts and
//     stops (velocity along a half cosine) within the first and last half corners, where the fast
//     axis is turning too. corner_s = 0 makes these kinks (unbounded acceleration).
//   - before start_s every axis holds where the raster starts; from T on (the settle, settle_s
//     long, and after it) where it ends. The fast axis is at rest there but, as at any corner's
//     centre, not free of acceleration (v pi / corner_s): holding takes that step in acceleration,
//     as trajectory.hpp's approach into a triangle does.
// Axes in neither role hold their centre.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <variant>

#include "loop/feasibility.hpp"
#include "loop/trajectory.hpp"
#include "models/axis_coupling.hpp"

namespace hystloop {

inline constexpr std::size_t kScanAxes = static_cast<std::size_t>(kMaxAxes);

// A raster's fast-axis share that differs from its own triangle by at most this is still periodic
// (ScanShare::periodic_part) [m]: a tenth of a nanometre, below any position sensor's noise.
inline constexpr double kPeriodicShareTolerance_m = 1e-10;
using AxisPositions = std::array<double, kScanAxes>;  // one reference per axis [m]

enum class SlowMode : std::int8_t { kSteps = 0, kRamp = 1 };

struct RasterSpec {
  static constexpr int kMaxLines = 4096;

  int fast_axis = 0;          // 0..kMaxAxes-1 (x, y, z)
  int slow_axis = 1;          // 0..kMaxAxes-1, not fast_axis
  double width_m = 0.0;       // fast-axis travel, peak to peak, > 0
  double height_m = 0.0;      // slow-axis travel from the first line to the last, >= 0
  int lines = 2;              // [2, kMaxLines]
  double line_rate_hz = 1.0;  // lines per second: the fast triangle's frequency is line_rate_hz / 2
  double corner_s = 0.0;      // the fast triangle's rounded corners [s], in [0, 1 / line_rate_hz); > 0 for steps
  AxisPositions centre_m{};   // the scan's centre per axis; axes outside the raster hold theirs
  SlowMode slow_mode = SlowMode::kSteps;
  double settle_s = 0.0;  // hold at the end, counted in the raster's duration [s]
  double start_s = 0.0;   // loop time of line 0's start [s]

  // Throws ParameterError naming the field ("raster.lines", ...).
  void validate() const;
};

// lines / line_rate_hz + settle_s [s].
double raster_duration_s(const RasterSpec& spec) noexcept;

// The fast axis alone as a 1-axis trajectory (the rounded triangle described above, its shape's
// tau = 0 at start_s): what evaluate() follows during the lines and what the feasibility check asks
// about.
TrajectorySpec raster_fast_trajectory(const RasterSpec& spec) noexcept;

// Each axis's reference at loop time t. Allocation- and throw-free; an unvalidated spec gives
// meaningless values but no undefined behaviour (axes out of range: every axis at its centre).
AxisPositions evaluate(const RasterSpec& spec, double t_s) noexcept;

// Where the raster is at t, for an error map indexed by line and position.
struct RasterPoint {
  int line = 0;              // 0..lines-1 (0 before the start, lines-1 from the end on)
  double along = 0.0;        // where the fast axis is along this line: 0 at its start, 1 at its end
  int direction = 1;         // +1: towards centre + width/2, -1: back
  bool on_straight = false;  // on a straight part: neither in a corner, nor before start or after the lines
};
RasterPoint raster_point(const RasterSpec& spec, double t_s) noexcept;

// A Lissajous figure: axis i is centre_m[i] + amplitude_m[i] sin(2 pi frequency_hz[i] tau +
// phase_rad[i]) for tau = t - start_s in [0, duration_s]; it holds its value at tau = 0 before and
// at duration_s after. An axis not at a peak or trough there starts and stops with the sine's
// velocity, a step the peaks and the feasibility check below do not include: approaching the path
// and leaving it (as the compensator's blend approaches a trajectory) is the caller's. An axis of
// amplitude 0 holds its centre.
struct LissajousSpec {
  AxisPositions amplitude_m{};                   // peak [m], >= 0; at least one axis > 0
  std::array<double, kScanAxes> frequency_hz{};  // > 0 on every moving axis
  std::array<double, kScanAxes> phase_rad{};
  AxisPositions centre_m{};
  double duration_s = 1.0;  // > 0
  double start_s = 0.0;

  // Throws ParameterError naming the field ("lissajous.frequency_hz", ...).
  void validate() const;
};

// Axis i of the figure as a 1-axis sine (start_s as the figure's).
TrajectorySpec lissajous_axis_trajectory(const LissajousSpec& spec, int axis) noexcept;

AxisPositions evaluate(const LissajousSpec& spec, double t_s) noexcept;

// What one axis of a path asks of the stage: the extent of its reference and the peak magnitudes
// of its derivatives (each over the whole path; they need not occur at the same time).
struct AxisPeaks {
  double min_m = 0.0;
  double max_m = 0.0;
  ShapePeaks derivatives{};
};
// Raster: the fast axis's are trajectory.hpp's triangle peaks; the slow axis's, per line spacing
// h = height / (lines - 1) moved within a corner c, 2 h / c, 2 pi h / c^2, 4 pi^2 h / c^3 (steps) or,
// for the ramp's slope s = height / (T - c/2), s, s pi / c, 2 s pi^2 / c^2. Holding axes: 0.
std::array<AxisPeaks, kScanAxes> raster_peaks(const RasterSpec& spec) noexcept;
// Lissajous: each axis's sine, (2 pi f)^n A.
std::array<AxisPeaks, kScanAxes> lissajous_peaks(const LissajousSpec& spec) noexcept;

// One axis's share of a decoupled path, what that axis's compensator follows:
//
//   w_a(t) = sum_j row_j r_j(t),
//
// r the path's reference per axis (a raster or a Lissajous figure, above) and row axis a's row of
// C^{-1} (models/axis_coupling.hpp), so that the stage, which couples the axes' own displacements
// by C, reaches r on every axis. With an identity row it is the path's own axis. Built once (the
// raster's triangle, the Lissajous sines), then at() per tick: allocation- and throw-free.
class ScanShare {
 public:
  // Validate the path (ParameterError naming its field) and the row ("scan.row": finite, and
  // non-zero at `axis`, whose own reference it must contain).
  ScanShare(const RasterSpec& raster, int axis, const AxisVector& row);
  ScanShare(const LissajousSpec& lissajous, int axis, const AxisVector& row);

  double at(double t_s) const noexcept;
  // The axis's own reference r_a(t), what its sensor must read, and its share w_a(t), what its own
  // displacement must be (the two differ by what the other axes' displacements add to the reading).
  struct Point {
    double own_m = 0.0;
    double share_m = 0.0;
  };
  Point point(double t_s) const noexcept;
  int axis() const noexcept { return axis_; }
  double start_s() const noexcept { return start_s_; }
  // From here on the path holds its last point for good (a raster's settle only holds it).
  double end_s() const noexcept { return end_s_; }
  const AxisVector& row() const noexcept { return row_; }
  // The path (std::get_if for the kind).
  const std::variant<RasterSpec, LissajousSpec>& path() const noexcept { return path_; }
  // Every path axis's reference at t (what each axis's share is made of).
  AxisPositions path_at(double t_s) const noexcept;
  // The fast axis's triangle when the share is a raster's fast axis alone (its row is that axis's
  // unit vector, up to entries that move the share by at most kPeriodicShareTolerance_m: an
  // identified coupling's near-zero ones): a periodic reference, period 2 / line_rate_hz, over
  // [start_s, start_s + lines / line_rate_hz), that learning can follow. nullptr otherwise.
  const TrajectorySpec* periodic_part() const noexcept { return periodic_ ? &shapes_[0] : nullptr; }

 private:
  std::variant<RasterSpec, LissajousSpec> path_;
  std::array<TrajectorySpec, kScanAxes> shapes_{};  // raster: [0] the fast triangle; Lissajous: each axis's sine
  int axis_ = 0;
  AxisVector row_ = AxisVector::Zero();
  double start_s_ = 0.0;
  double end_s_ = 0.0;
  bool periodic_ = false;
};

// One axis's actuator: feasibility.hpp's plant and limits.
struct AxisActuator {
  LinearPlant plant;
  FeedforwardLimits limits;
};

// The verdict of checking a path against each axis's actuator.
struct ScanFeasibility {
  std::array<VoltageNeed, kScanAxes> needs{};  // per axis; entries >= the number of actuators: 0
  int axis = -1;                               // the first axis that does not fit; -1 when all do
  Limit limit = Limit::kNone;                  // which of its limits it breaks
  std::string reason;  // "x (fast axis) exceeds its slew limit: needs 67398.2 V/s, 50000 V/s usable"; empty when ok
  bool ok() const noexcept { return limit == Limit::kNone; }
};

// Every axis of the stage (actuators[i] is axis i; the path's axes must be among them) against its
// limits, in axis order: the fast axis and the Lissajous axes by feasibility.hpp's exact closed
// forms (voltage_need of the 1-axis trajectory above); the raster's slow axis, whose shape has no
// closed form there, by a bound from its peaks, u = (y + (c/k) y' + y''/k) / g with each term at
// its peak (exact without the stage, on the safe side with it); axes outside the path by holding
// their centre. Validates the spec, the plants ("x.plant.gain_m_per_V") and the limits
// ("x.limits.slew_V_per_s"): ParameterError; a path axis without an actuator names the axis field.
ScanFeasibility check_raster_feasible(const RasterSpec& spec, std::span<const AxisActuator> actuators);
ScanFeasibility check_lissajous_feasible(const LissajousSpec& spec, std::span<const AxisActuator> actuators);

}  // namespace hystloop
