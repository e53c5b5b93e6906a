#include "loop/multi_axis_bridge.hpp"

#include <algorithm>
#include <string>

#include "core/errors.hpp"

namespace hystloop {

namespace {

int checked_axes(int axes, std::size_t limits, std::size_t servo) {
  if (axes < 1 || axes > kMaxAxes) {
    throw ParameterError("axes", "must be 1 to " + std::to_string(kMaxAxes) + " (got " + std::to_string(axes) + ")");
  }
  const auto n = static_cast<std::size_t>(axes);
  if (limits != n || servo != n) {
    throw ParameterError("axes", std::to_string(axes) + " axes need one actuator and one servo each (got " +
                                     std::to_string(limits) + " actuators, " + std::to_string(servo) + " servos)");
  }
  return axes;
}

// Axis i's core; axes past the stage's are never ticked (default limits, no servo).
BridgeCore make_core(int i, int axes, std::span<const ActuatorLimits> limits, std::span<const FeedbackGains> servo,
                     double dt_s) {
  if (i >= axes) return BridgeCore(ActuatorLimits{}, FeedbackGains{}, dt_s);
  const auto at = static_cast<std::size_t>(i);
  try {
    limits[at].validate();
    servo[at].validate();
  } catch (const ParameterError& e) {
    throw ParameterError(axis_field(e.field(), i), e.reason());  // the axis's own key: actuator.y.slew_V_per_s
  }
  return BridgeCore(limits[at], servo[at], dt_s);
}

}  // namespace

MultiAxisBridge::MultiAxisBridge(int axes, std::span<const ActuatorLimits> limits, std::span<const FeedbackGains> servo,
                                 double dt_s)
    : axes_(checked_axes(axes, limits.size(), servo.size())),
      cores_{make_core(0, axes, limits, servo, dt_s), make_core(1, axes, limits, servo, dt_s),
             make_core(2, axes, limits, servo, dt_s)} {
  static_assert(kMaxAxes == 3, "cores_ is built one initialiser per axis");
}

namespace {
template <class T>
std::array<T, kMaxAxes> filled(const T& value) {
  std::array<T, kMaxAxes> a;
  a.fill(value);
  return a;
}
std::size_t axes_or_none(int axes) { return axes >= 1 && axes <= kMaxAxes ? static_cast<std::size_t>(axes) : 0; }
}  // namespace

MultiAxisBridge::MultiAxisBridge(int axes, const ActuatorLimits& limits, const FeedbackGains& servo, double dt_s)
    : MultiAxisBridge(axes, std::span<const ActuatorLimits>(filled(limits)).first(axes_or_none(axes)),
                      std::span<const FeedbackGains>(filled(servo)).first(axes_or_none(axes)), dt_s) {}

bool MultiAxisBridge::submit(int axis, const CommandTick& command) noexcept {
  if (axis < 0 || axis >= axes_) {
    ++misaddressed_;
    return false;
  }
  return cores_[static_cast<std::size_t>(axis)].submit(command);
}

void MultiAxisBridge::tick(std::int64_t k, std::span<const double> y_m, std::span<BridgeTick> out) noexcept {
  // Decided before any axis applies tick k, so that every axis enters the safe state on it. (An armed
  // stage with a disarmed axis cannot arise through this interface; it would trip the stage too.)
  if (armed_) {
    for (int i = 0; i < axes_; ++i) {
      const BridgeCore& core = cores_[static_cast<std::size_t>(i)];
      if (!core.watchdog_due(k) && core.armed()) continue;
      ++stage_trips_;
      tripped_by_ = i;
      disarm();
      break;
    }
  }
  for (std::size_t i = 0; i < static_cast<std::size_t>(axes_); ++i) out[i] = cores_[i].tick(k, y_m[i]);
}

void MultiAxisBridge::arm(std::int64_t k) noexcept {
  for (std::size_t i = 0; i < static_cast<std::size_t>(axes_); ++i) cores_[i].arm(k);
  armed_ = true;
}

std::int64_t MultiAxisBridge::buffer_depth() const noexcept {
  std::int64_t depth = cores_[0].buffer_depth();
  for (std::size_t i = 1; i < static_cast<std::size_t>(axes_); ++i) depth = std::min(depth, cores_[i].buffer_depth());
  return depth;
}

void MultiAxisBridge::set_max_lead_ticks(std::int64_t ticks) {
  for (BridgeCore& core : cores_) core.set_max_lead_ticks(ticks);
}

void MultiAxisBridge::set_servo_gains(int axis, const FeedbackGains& gains) noexcept {
  if (axis >= 0 && axis < axes_) cores_[static_cast<std::size_t>(axis)].set_servo_gains(gains);
}

BridgeCounters MultiAxisBridge::counters() const noexcept {
  BridgeCounters sum = cores_[0].counters();
  for (std::size_t i = 1; i < static_cast<std::size_t>(axes_); ++i) {
    const BridgeCounters& c = cores_[i].counters();
    sum.applied += c.applied;
    sum.late += c.late;
    sum.stale += c.stale;
    sum.duplicates += c.duplicates;
    sum.rejected_nonfinite += c.rejected_nonfinite;
    sum.rejected_future += c.rejected_future;
    sum.clamped += c.clamped;
    sum.slew_limited += c.slew_limited;
    sum.clamped_either += c.clamped_either;
  }
  // A stage trip disarms every core before its tick, so no core counts it as its own.
  sum.watchdog_trips = stage_trips_;
  return sum;
}

ClampCounts MultiAxisBridge::clamped_last_second() const noexcept {
  ClampCounts sum{};
  for (std::size_t i = 0; i < static_cast<std::size_t>(axes_); ++i) {
    const ClampCounts& c = cores_[i].clamped_last_second();
    sum.either += c.either;
    sum.range += c.range;
    sum.slew += c.slew;
  }
  return sum;
}

void MultiAxisBridge::disarm() noexcept {
  for (std::size_t i = 0; i < static_cast<std::size_t>(axes_); ++i) cores_[i].disarm();
  armed_ = false;
}

}  // namespace hystloop
