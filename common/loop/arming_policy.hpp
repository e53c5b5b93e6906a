#pragma once
// The bridge's arming rules, without threads or a clock (time is the tick argument): who may arm
// BridgeCore and when. An operator's ARM arms, DISARM disarms and ends every automatic arming; the
// stop disarms for good; `auto_arm` arms once when commands first flow; `rearm_after_trip_s` > 0
// (opt-in, for soak runs) re-arms that long after a watchdog trip once commands are buffered again.
// BridgeRealtime calls it at every tick around BridgeCore::tick.

#include <cstdint>

#include "loop/bridge_core.hpp"

namespace hystloop {

enum class ArmRequest : std::uint8_t { kNone = 0, kArm = 1, kDisarm = 2 };

struct ArmingSettings {
  bool auto_arm = false;            // arm as soon as commands flow (first arm only)
  double rearm_after_trip_s = 0.0;  // > 0: re-arm this long after a watchdog trip (0 = never)
  double dt_s = 1e-4;               // the tick [s]
};

class ArmingPolicy {
 public:
  explicit ArmingPolicy(const ArmingSettings& settings) noexcept
      : settings_(settings), auto_arm_pending_(settings.auto_arm) {}

  // From this call on the core is disarmed and never armed again (the safe stop). Idempotent.
  void stop(BridgeCore& core) noexcept;
  // An operator's request, taken at tick k.
  void request(ArmRequest request, std::int64_t k, BridgeCore& core) noexcept;
  // After the tick's commands were submitted, before core.tick(k): the automatic arming.
  // `commands_seen`: any command was ever submitted.
  void before_tick(std::int64_t k, bool commands_seen, BridgeCore& core) noexcept;
  // After core.tick(k): notices a watchdog trip.
  void after_tick(std::int64_t k, const BridgeCore& core) noexcept;

  bool stopping() const noexcept { return stopping_; }
  bool tripped() const noexcept { return tripped_; }  // safe because of the watchdog, not an operator
  std::uint64_t auto_arms() const noexcept { return auto_arms_; }
  std::int64_t last_trip_tick() const noexcept { return last_trip_tick_; }  // -1: none

 private:
  ArmingSettings settings_;
  bool auto_arm_pending_;
  bool tripped_ = false;
  bool stopping_ = false;
  std::uint64_t auto_arms_ = 0;
  std::uint64_t trips_seen_ = 0;
  std::int64_t last_trip_tick_ = -1;
};

}  // namespace hystloop
