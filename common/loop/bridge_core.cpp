#include "loop/bridge_core.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/errors.hpp"

namespace hystloop {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The servo's anti-windup range and notch design follow the actuator and the clock, whoever sets the gains.
FeedbackGains with_actuator_limit(FeedbackGains gains, const ActuatorLimits& limits, double dt_s) {
  gains.u_min_V = limits.u_min_V;
  gains.u_max_V = limits.u_max_V;
  gains.tick_rate_hz = 1.0 / dt_s;
  return gains;
}

}  // namespace

void ActuatorLimits::validate() const {
  require_finite("actuator.u_min_V", u_min_V);
  require_finite("actuator.u_max_V", u_max_V);
  if (!(u_max_V > u_min_V)) throw ParameterError("actuator.u_max_V", "must be greater than actuator.u_min_V");
  require_positive("actuator.slew_V_per_s", slew_V_per_s);
  require_in_range("actuator.safe_u_V", safe_u_V, u_min_V, u_max_V);
  require_positive("actuator.safe_ramp_V_per_s", safe_ramp_V_per_s);
  require_positive("actuator.watchdog_s", watchdog_s);
  if (std::isnan(position_min_m) || std::isnan(position_max_m) || !(position_max_m > position_min_m)) {
    throw ParameterError("actuator.position_max_m", "must be greater than actuator.position_min_m");
  }
}

BridgeCore::BridgeCore(const ActuatorLimits& limits, const FeedbackGains& servo, double dt_s)
    : limits_((limits.validate(), limits)),
      dt_s_((require_positive("bridge.dt_s", dt_s), dt_s)),
      // Whole ticks: k * dt compared with watchdog_s in floating point trips a tick early for
      // about a third of the values (0.0003 s = 3 ticks reads as 3.0000000000000004e-4).
      watchdog_ticks_(static_cast<std::int64_t>(std::floor(limits.watchdog_s / dt_s + 1e-9))),
      servo_(with_actuator_limit(servo, limits, dt_s)),
      servo_ref_m_(kNaN),
      ticks_per_second_(std::max<std::int64_t>(1, std::llround(1.0 / dt_s))) {
  u_applied_ = limits_.safe_u_V;
  held_.u_ff_V = limits_.safe_u_V;
  held_.y_ref_m = kNaN;
}

bool BridgeCore::submit(const CommandTick& command) noexcept {
  if (!std::isfinite(command.u_ff_V) || std::isinf(command.y_ref_m)) {
    ++counters_.rejected_nonfinite;
    return false;
  }
  if (command.seq - buffer_.next_tick() > max_lead_ticks_) {
    ++counters_.rejected_future;
    return false;
  }
  switch (buffer_.insert(command)) {
    case CommandBuffer::Insert::kStored: return true;
    case CommandBuffer::Insert::kDuplicate: ++counters_.duplicates; return false;
    case CommandBuffer::Insert::kStale: ++counters_.stale; return false;
    case CommandBuffer::Insert::kTooFarAhead: ++counters_.rejected_future; return false;
  }
  return false;
}

void BridgeCore::set_max_lead_ticks(std::int64_t ticks) {
  if (ticks < 1 || ticks > CommandBuffer::kCapacityTicks) {
    throw ParameterError("bridge.max_lead_s", "must be between one tick and the command buffer's " +
                                                  std::to_string(CommandBuffer::kCapacityTicks) + " ticks");
  }
  max_lead_ticks_ = ticks;
}

void BridgeCore::set_servo_gains(const FeedbackGains& gains) noexcept {
  try {
    servo_.set_gains(with_actuator_limit(gains, limits_, dt_s_));
  } catch (...) {  // validated by the caller; an invalid set keeps the gains in force
  }
}

void BridgeCore::roll_clamp_window(std::int64_t k) noexcept {
  const std::int64_t second = k / ticks_per_second_;
  if (second == clamp_second_) return;
  clamp_last_second_ = second == clamp_second_ + 1 ? clamp_this_second_ : ClampCounts{};
  clamp_this_second_ = {};
  clamp_second_ = second;
}

BridgeTick BridgeCore::tick(std::int64_t k, double y_measured_m) noexcept {
  ++counters_.ticks;
  roll_clamp_window(k);
  const double step_s =
      last_tick_ >= 0 ? dt_s_ * static_cast<double>(std::max<std::int64_t>(1, k - last_tick_)) : dt_s_;
  last_tick_ = k;
  BridgeTick out;
  const CommandTick* command = buffer_.take(k);
  out.buffer_depth = buffer_.depth();

  if (armed_ && command == nullptr && k - last_supplied_tick_ > watchdog_ticks_) {
    armed_ = false;
    ++counters_.watchdog_trips;
  }

  if (!armed_) {
    // Safe state: ramp to the safe voltage; the servo holds its state for the re-arm.
    out.flags |= sample_flags::kSafeState;
    out.y_ref_m = kNaN;
    servo_ref_m_ = kNaN;
    ++counters_.safe_ticks;
    // The ramp is anchored at the voltage it started from and counts whole ticks (never faster
    // than the slew limit), so no rounding accumulates: it arrives exactly at safe_u_V, within
    // ceil(|u0 - safe_u_V| / (rate * dt)) ticks.
    if (!safe_ramp_active_) {
      safe_ramp_active_ = true;
      safe_ramp_from_V_ = u_applied_;
      safe_ramp_ticks_ = 0;
    }
    ++safe_ramp_ticks_;
    const double distance = limits_.safe_u_V - safe_ramp_from_V_;
    const double travelled = static_cast<double>(safe_ramp_ticks_) * limits_.safe_ramp_rate_V_per_s() * dt_s_;
    u_applied_ =
        travelled >= std::abs(distance) ? limits_.safe_u_V : safe_ramp_from_V_ + std::copysign(travelled, distance);
    out.u_applied_V = u_applied_;
    return out;
  }
  safe_ramp_active_ = false;
  if (command != nullptr) {
    held_ = *command;
    last_supplied_tick_ = k;
    command_since_arm_ = true;
    ++counters_.applied;
  } else {
    ++counters_.late;
    out.flags |= sample_flags::kLateCommand;
  }
  // What the clamps below will let through this tick: the range, and the slew limit's reach from
  // the voltage applied last. The servo integrates only while its command stays inside.
  const double max_step = limits_.slew_V_per_s * dt_s_;
  const double allowed_lo_V = std::max(limits_.u_min_V, u_applied_ - max_step);
  const double allowed_hi_V = std::min(limits_.u_max_V, u_applied_ + max_step);
  // The servo: the previous tick's reference against the position measured at its end.
  if (!command_since_arm_) {
    // Re-armed, no command yet: the servo keeps what it held through the safe state.
  } else if (!std::isfinite(held_.y_ref_m)) {
    servo_.reset();  // no reference (an experiment): nothing to track, nothing to remember
  } else if (std::isfinite(servo_ref_m_) && servo_.gains().enabled()) {
    out.u_fb_V = servo_.update(servo_ref_m_ - y_measured_m, held_.u_ff_V, step_s, allowed_lo_V, allowed_hi_V);
  }
  servo_ref_m_ = held_.y_ref_m;
  out.u_ff_V = held_.u_ff_V;
  out.y_ref_m = held_.y_ref_m;
  out.params_version = held_.params_version;
  const double target = held_.u_ff_V + out.u_fb_V;

  const double clamped = std::clamp(target, limits_.u_min_V, limits_.u_max_V);
  const bool range_clamped = clamped != target;
  double u = clamped;
  const bool slew_clamped = std::abs(u - u_applied_) > max_step;
  if (slew_clamped) u = u_applied_ + std::copysign(max_step, u - u_applied_);
  if (range_clamped) {
    ++counters_.clamped;
    ++clamp_this_second_.range;
    out.flags |= sample_flags::kSaturated;
  }
  if (slew_clamped) {
    ++counters_.slew_limited;
    ++clamp_this_second_.slew;
    out.flags |= sample_flags::kSlewLimited;
  }
  if (range_clamped || slew_clamped) {
    ++counters_.clamped_either;
    ++clamp_this_second_.either;
  }
  u_applied_ = u;
  out.u_applied_V = u;
  return out;
}

void BridgeCore::arm(std::int64_t k) noexcept {
  armed_ = true;
  // Hold where we are until the first command's tick; the watchdog counts from now.
  held_.u_ff_V = u_applied_;
  held_.y_ref_m = kNaN;
  held_.params_version = 0;
  servo_ref_m_ = kNaN;
  last_supplied_tick_ = k;
  command_since_arm_ = false;
}

void BridgeCore::disarm() noexcept { armed_ = false; }

}  // namespace hystloop
