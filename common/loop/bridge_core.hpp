#pragma once
// The bridge's decision logic, without I/O or a clock: which voltage reaches the
// actuator at tick k. It owns the safety rules of DESIGN.md — range and slew clamp,
// non-finite and stale rejection, the watchdog and the safe-state ramp — so that
// they are tested here, faster than real time, and the service only wires I/O to it.

#include <array>
#include <cstdint>

namespace hystloop {

// Bits of sensor_sample_t.flags (the LCM type repeats these values).
namespace sample_flags {
inline constexpr std::int32_t kSaturated = 1;     // the command was clamped to the range
inline constexpr std::int32_t kSafeState = 2;     // watchdog tripped or not armed: ramping to / holding safe_u_V
inline constexpr std::int32_t kSimulated = 4;     // the stage is the built-in simulator
inline constexpr std::int32_t kSlewLimited = 8;   // the command was slew-limited
inline constexpr std::int32_t kLateCommand = 16;  // no command for this tick: the last one was held
}  // namespace sample_flags

struct ActuatorLimits {
  double u_min_V = -250.0;
  double u_max_V = 250.0;
  double slew_V_per_s = 5.0e4;       // 5 V per 100 us tick; the MEM paper's 250 V, 10 Hz sine needs 1.6e4 V/s
  double safe_u_V = 0.0;             // where the watchdog takes the actuator
  double safe_ramp_V_per_s = 1.0e3;  // how fast it goes there (250 V in 0.25 s)
  double watchdog_s = 2.0e-3;        // no fresh command for this long -> safe state

  void validate() const;  // throws ParameterError naming the field
};

struct BridgeCounters {
  std::uint64_t ticks = 0;
  std::uint64_t applied = 0;            // ticks that applied a command meant for them
  std::uint64_t late = 0;               // armed ticks with no command for them (last one held)
  std::uint64_t stale = 0;              // commands that arrived after their tick had passed
  std::uint64_t rejected_nonfinite = 0;
  std::uint64_t rejected_future = 0;    // seq too far ahead to buffer
  std::uint64_t clamped = 0;
  std::uint64_t slew_limited = 0;
  std::uint64_t watchdog_trips = 0;
  std::uint64_t ignored_disarmed = 0;   // commands received while in the safe state
};

struct BridgeTick {
  double u_applied_V = 0.0;
  std::int32_t flags = 0;
  std::int32_t params_version = 0;      // of the command applied (0 when none)
};

class BridgeCore {
 public:
  static constexpr std::int64_t kBufferTicks = 64;  // how far ahead a command may be sent

  explicit BridgeCore(const ActuatorLimits& limits, double dt_s = 1e-4);

  // A command for tick `seq`, received at loop time now_s. Returns false if rejected.
  bool submit(std::int64_t seq, double u_V, std::int32_t params_version, double now_s) noexcept;

  // Decide the voltage for tick k at loop time t_s (k increases by one per call).
  BridgeTick tick(std::int64_t k, double t_s) noexcept;

  // Leave the safe state: commands are applied again, reached from the current voltage
  // under the slew limit. Disarm enters the safe state at once.
  void arm(double now_s) noexcept;
  void disarm() noexcept;
  bool armed() const noexcept { return armed_; }

  const BridgeCounters& counters() const noexcept { return counters_; }
  const ActuatorLimits& limits() const noexcept { return limits_; }
  double last_applied_V() const noexcept { return u_applied_; }

 private:
  struct Slot {
    std::int64_t seq = -1;
    double u_V = 0.0;
    std::int32_t params_version = 0;
  };

  ActuatorLimits limits_;
  double dt_s_;
  std::array<Slot, kBufferTicks> slots_{};
  std::int64_t next_tick_ = 0;     // the tick tick() will be called with next
  double last_fresh_s_ = -1e300;   // when the last accepted command arrived
  double u_applied_ = 0.0;         // last voltage applied (starts at the safe voltage)
  double u_held_ = 0.0;            // last command applied, held when one is late
  std::int32_t held_version_ = 0;
  bool armed_ = false;
  BridgeCounters counters_;
};

}  // namespace hystloop
