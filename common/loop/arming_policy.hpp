#pragma once
// The bridge's arming rules, without threads or a clock (time is the tick argument): who may arm
// the stage and when. An operator's ARM arms, DISARM disarms and ends every automatic arming; the
// stop disarms for good; `auto_arm` arms once when commands first flow; `rearm_after_trip_s` > 0
// (opt-in, for soak runs) re-arms that long after a watchdog trip once commands are buffered again.
// BridgeRealtime calls it at every tick around the stage's tick. The stage is a BridgeCore (one
// axis) or a MultiAxisBridge (every axis armed and disarmed together): anything with the members
// ArmableStage names.

#include <concepts>
#include <cstdint>

namespace hystloop {

enum class ArmRequest : std::uint8_t { kNone = 0, kArm = 1, kDisarm = 2 };

template <class S>
concept ArmableStage = requires(S s, const S& cs, std::int64_t k) {
  s.arm(k);
  s.disarm();
  { cs.armed() } -> std::convertible_to<bool>;
  { cs.buffer_depth() } -> std::convertible_to<std::int64_t>;  // ticks buffered ahead (every axis: the least)
  { cs.watchdog_trips() } -> std::convertible_to<std::uint64_t>;
};

struct ArmingSettings {
  bool auto_arm = false;            // arm as soon as commands flow (first arm only)
  double rearm_after_trip_s = 0.0;  // > 0: re-arm this long after a watchdog trip (0 = never)
  double dt_s = 1e-4;               // the tick [s]
};

class ArmingPolicy {
 public:
  explicit ArmingPolicy(const ArmingSettings& settings) noexcept
      : settings_(settings), auto_arm_pending_(settings.auto_arm) {}

  // From this call on the stage is disarmed and never armed again (the safe stop). Idempotent.
  template <ArmableStage S>
  void stop(S& stage) noexcept {
    if (stopping_) return;
    stopping_ = true;
    stage.disarm();
    auto_arm_pending_ = false;
    tripped_ = false;
  }

  // An operator's request, taken at tick k.
  template <ArmableStage S>
  void request(ArmRequest request, std::int64_t k, S& stage) noexcept {
    switch (request) {
      case ArmRequest::kArm:
        if (stopping_) return;
        stage.arm(k);
        tripped_ = false;
        return;
      case ArmRequest::kDisarm:
        stage.disarm();
        auto_arm_pending_ = false;  // an explicit disarm ends the convenience ...
        tripped_ = false;           // ... and an operator's disarm is never undone automatically
        return;
      case ArmRequest::kNone: return;
    }
  }

  // After the tick's commands were submitted, before the stage's tick k: the automatic arming.
  // `commands_seen`: any command was ever submitted.
  template <ArmableStage S>
  void before_tick(std::int64_t k, bool commands_seen, S& stage) noexcept {
    if (commands_seen && stage.buffer_depth() > 0 && !stage.armed() && !stopping_) {
      if (auto_arm_pending_) {
        stage.arm(k);
        auto_arm_pending_ = false;
        ++auto_arms_;
      } else if (tripped_ && settings_.rearm_after_trip_s > 0.0 &&
                 static_cast<double>(k - last_trip_tick_) * settings_.dt_s >= settings_.rearm_after_trip_s) {
        stage.arm(k);
        tripped_ = false;
        ++auto_arms_;
      }
    }
    if (stage.armed()) auto_arm_pending_ = false;  // armed by an operator: no auto-arm later
  }

  // After the stage's tick k: notices a watchdog trip.
  template <ArmableStage S>
  void after_tick(std::int64_t k, const S& stage) noexcept {
    if (stage.watchdog_trips() != trips_seen_) {
      trips_seen_ = stage.watchdog_trips();
      last_trip_tick_ = k;
      tripped_ = true;
    }
  }

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
