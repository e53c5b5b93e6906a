#include "loop/bridge_core.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"

namespace hystloop {

void ActuatorLimits::validate() const {
  require_finite("actuator.u_min_V", u_min_V);
  require_finite("actuator.u_max_V", u_max_V);
  if (!(u_max_V > u_min_V)) throw ParameterError("actuator.u_max_V", "must be greater than actuator.u_min_V");
  require_positive("actuator.slew_V_per_s", slew_V_per_s);
  require_in_range("actuator.safe_u_V", safe_u_V, u_min_V, u_max_V);
  require_positive("actuator.safe_ramp_V_per_s", safe_ramp_V_per_s);
  require_positive("actuator.watchdog_s", watchdog_s);
}

BridgeCore::BridgeCore(const ActuatorLimits& limits, double dt_s) : limits_(limits), dt_s_(dt_s) {
  limits_.validate();
  require_positive("bridge.dt_s", dt_s);
  u_applied_ = limits_.safe_u_V;
  u_held_ = limits_.safe_u_V;
}

bool BridgeCore::submit(std::int64_t seq, double u_V, std::int32_t params_version, double now_s) noexcept {
  if (!std::isfinite(u_V)) {
    ++counters_.rejected_nonfinite;
    return false;
  }
  if (seq < next_tick_) {
    ++counters_.stale;
    return false;
  }
  if (seq >= next_tick_ + kBufferTicks) {
    ++counters_.rejected_future;
    return false;
  }
  if (!armed_) {
    ++counters_.ignored_disarmed;
    last_fresh_s_ = now_s;  // the command stream is alive: arm() may rely on it
    return false;
  }
  slots_[static_cast<std::size_t>(seq % kBufferTicks)] = Slot{seq, u_V, params_version};
  last_fresh_s_ = now_s;
  return true;
}

BridgeTick BridgeCore::tick(std::int64_t k, double t_s) noexcept {
  ++counters_.ticks;
  next_tick_ = k + 1;
  BridgeTick out;

  if (armed_ && t_s - last_fresh_s_ > limits_.watchdog_s) {
    armed_ = false;
    ++counters_.watchdog_trips;
  }

  double target;
  double max_step;
  if (!armed_) {
    target = limits_.safe_u_V;
    max_step = limits_.safe_ramp_V_per_s * dt_s_;
    out.flags |= sample_flags::kSafeState;
  } else {
    Slot& slot = slots_[static_cast<std::size_t>(k % kBufferTicks)];
    if (slot.seq == k) {
      u_held_ = slot.u_V;
      held_version_ = slot.params_version;
      ++counters_.applied;
    } else {
      ++counters_.late;
      out.flags |= sample_flags::kLateCommand;
    }
    target = u_held_;
    max_step = limits_.slew_V_per_s * dt_s_;
    out.params_version = held_version_;
  }

  const double clamped = std::clamp(target, limits_.u_min_V, limits_.u_max_V);
  if (clamped != target) {
    ++counters_.clamped;
    out.flags |= sample_flags::kSaturated;
  }
  double u = clamped;
  if (std::abs(u - u_applied_) > max_step) {
    u = u_applied_ + std::copysign(max_step, u - u_applied_);
    if (armed_) {
      ++counters_.slew_limited;
      out.flags |= sample_flags::kSlewLimited;
    }
  }
  u_applied_ = u;
  out.u_applied_V = u;
  return out;
}

void BridgeCore::arm(double now_s) noexcept {
  armed_ = true;
  // Hold where we are until the first command arrives; the watchdog starts now.
  u_held_ = u_applied_;
  last_fresh_s_ = std::max(last_fresh_s_, now_s);
}

void BridgeCore::disarm() noexcept { armed_ = false; }

}  // namespace hystloop
