#include "loop/arming_policy.hpp"

namespace hystloop {

void ArmingPolicy::stop(BridgeCore& core) noexcept {
  if (stopping_) return;
  stopping_ = true;
  core.disarm();
  auto_arm_pending_ = false;
  tripped_ = false;
}

void ArmingPolicy::request(ArmRequest request, std::int64_t k, BridgeCore& core) noexcept {
  switch (request) {
    case ArmRequest::kArm:
      if (stopping_) return;
      core.arm(k);
      tripped_ = false;
      return;
    case ArmRequest::kDisarm:
      core.disarm();
      auto_arm_pending_ = false;  // an explicit disarm ends the convenience ...
      tripped_ = false;           // ... and an operator's disarm is never undone automatically
      return;
    case ArmRequest::kNone: return;
  }
}

void ArmingPolicy::before_tick(std::int64_t k, bool commands_seen, BridgeCore& core) noexcept {
  if (commands_seen && core.buffer_depth() > 0 && !core.armed() && !stopping_) {
    if (auto_arm_pending_) {
      core.arm(k);
      auto_arm_pending_ = false;
      ++auto_arms_;
    } else if (tripped_ && settings_.rearm_after_trip_s > 0.0 &&
               static_cast<double>(k - last_trip_tick_) * settings_.dt_s >= settings_.rearm_after_trip_s) {
      core.arm(k);
      tripped_ = false;
      ++auto_arms_;
    }
  }
  if (core.armed()) auto_arm_pending_ = false;  // armed by an operator: no auto-arm later
}

void ArmingPolicy::after_tick(std::int64_t k, const BridgeCore& core) noexcept {
  if (core.counters().watchdog_trips != trips_seen_) {
    trips_seen_ = core.counters().watchdog_trips;
    last_trip_tick_ = k;
    tripped_ = true;
  }
}

}  // namespace hystloop
