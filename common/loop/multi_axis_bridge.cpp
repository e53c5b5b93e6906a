#include "loop/multi_axis_bridge.hpp"

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
  validate_within(std::string(axis_name(i)) + ".", [&] {
    limits[at].validate();
    servo[at].validate();
  });
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

void MultiAxisBridge::disarm() noexcept {
  for (std::size_t i = 0; i < static_cast<std::size_t>(axes_); ++i) cores_[i].disarm();
  armed_ = false;
}

}  // namespace hystloop
