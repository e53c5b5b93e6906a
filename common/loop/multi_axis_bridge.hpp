#pragma once
// The bridge's logic for a stage of several axes on one tick clock: per axis a BridgeCore (its
// actuator's limits, servo, jitter buffer and safe ramp), and one safe state for the whole stage.
// An axis whose watchdog is due takes every axis to the safe state on the same tick: the axes of a flexure stage share
// the moving platform, and one axis holding a scan's voltage while another ramps to its safe voltage would drive the
// platform along a path nobody planned (and, with the coupling, against the other axis's servo). All axes then ramp to
// their safe voltages together, each at its own safe_ramp_V_per_s, and are armed again together.

#include <array>
#include <cstdint>
#include <span>

#include "loop/bridge_core.hpp"
#include "models/axis_coupling.hpp"

namespace hystloop {

class MultiAxisBridge {
 public:
  // axes in 1..kMaxAxes; limits and servo hold one entry per axis (ParameterError naming the
  // axis: "actuator.y.slew_V_per_s", or "axes" for a count that does not match).
  MultiAxisBridge(int axes, std::span<const ActuatorLimits> limits, std::span<const FeedbackGains> servo,
                  double dt_s = 1e-4);
  // Every axis with the same actuator limits and servo.
  MultiAxisBridge(int axes, const ActuatorLimits& limits, const FeedbackGains& servo, double dt_s = 1e-4);

  // A command for one axis (axis outside 0..axes()-1: refused, counted in misaddressed()).
  bool submit(int axis, const CommandTick& command) noexcept;

  // Every axis's tick k: y_m[i] is axis i's position measured at the end of the previous tick,
  // out[i] its tick (both at least axes() long). One axis's watchdog trips the stage. A stage trip
  // is counted here (stage_trips; which axis: tripped_by), not by the cores: every core is disarmed first.
  void tick(std::int64_t k, std::span<const double> y_m, std::span<BridgeTick> out) noexcept;

  void arm(std::int64_t k) noexcept;  // every axis
  void disarm() noexcept;             // every axis: the safe state
  bool armed() const noexcept { return armed_; }
  // Ticks buffered ahead on the axis with the fewest: what the stage can run without new commands.
  std::int64_t buffer_depth() const noexcept;
  // The stage's watchdog trips (stage_trips()): with one axis, what its BridgeCore alone would count.
  std::uint64_t watchdog_trips() const noexcept { return stage_trips_; }

  // Every axis: the most commands may run ahead of the clock (BridgeCore::set_max_lead_ticks).
  void set_max_lead_ticks(std::int64_t ticks);
  // One axis's servo gains (validated by the caller), bumplessly; axis outside the stage: ignored.
  void set_servo_gains(int axis, const FeedbackGains& gains) noexcept;

  // The stage's counters: events summed over the axes (applied, late, clamped, ...: with one axis its
  // core's), the stage's ticks and safe ticks once (every axis ticks together), watchdog_trips the
  // stage's trips. An axis's own counters: axis(i).counters().
  BridgeCounters counters() const noexcept;
  // Armed ticks clamped in the last whole second, summed over the axes.
  ClampCounts clamped_last_second() const noexcept;

  int axes() const noexcept { return axes_; }
  // One axis's core, to read (arming and disarming go through the stage: arm(), disarm()).
  const BridgeCore& axis(int i) const noexcept { return cores_[static_cast<std::size_t>(i)]; }
  // How often one axis took the stage to the safe state, and which axis did it last (-1: none).
  std::uint64_t stage_trips() const noexcept { return stage_trips_; }
  int tripped_by() const noexcept { return tripped_by_; }
  std::uint64_t misaddressed() const noexcept { return misaddressed_; }

 private:
  int axes_;
  std::array<BridgeCore, kMaxAxes> cores_;
  bool armed_ = false;
  std::uint64_t stage_trips_ = 0;
  int tripped_by_ = -1;
  std::uint64_t misaddressed_ = 0;
};

}  // namespace hystloop
