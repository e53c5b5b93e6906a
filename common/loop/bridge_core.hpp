#pragma once
// The bridge's decision logic, without I/O or a clock: which voltage reaches the actuator at
// tick k. The compensator sends its feedforward and reference ahead of time; they wait in a
// jitter buffer indexed by tick (CommandBuffer). At tick k the core takes the command for k
// (or holds the last one: a late tick), adds the servo's correction on y_ref - y, clamps to the
// actuator's range and slew rate, and applies. The servo is told the interval both clamps leave
// this tick, so its anti-windup sees every clamp. It owns the safety rules of docs/TIMING.md: range and
// slew clamp, non-finite and stale rejection, the watchdog on an empty buffer and the ramp to
// the safe voltage. Time is an argument, so all of it is tested faster than real time.

#include <cstdint>
#include <limits>

#include "core/ticks.hpp"
#include "loop/command_buffer.hpp"
#include "loop/feedback.hpp"

namespace hystloop {

// Bits of sensor_block_t.flags (the LCM type repeats these values).
namespace sample_flags {
inline constexpr std::int32_t kSaturated = 1;     // the command was clamped to the range
inline constexpr std::int32_t kSafeState = 2;     // watchdog tripped or not armed: ramping to / holding safe_u_V
inline constexpr std::int32_t kSimulated = 4;     // the stage is the built-in simulator
inline constexpr std::int32_t kSlewLimited = 8;   // the command was slew-limited
inline constexpr std::int32_t kLateCommand = 16;  // no command for this tick: the last feedforward was held
inline constexpr std::int32_t kSensorFault = 32;  // the backend reports the sensor reading unreliable
}  // namespace sample_flags

struct ActuatorLimits {
  double u_min_V = -250.0;
  double u_max_V = 250.0;
  double slew_V_per_s = 5.0e4;       // 5 V per 100 us tick; the MEM paper's 250 V, 10 Hz sine needs 1.6e4 V/s
  double safe_u_V = 0.0;             // where the watchdog takes the actuator
  double safe_ramp_V_per_s = 1.0e3;  // how fast it goes there (250 V in 0.25 s)
  double watchdog_s = 2.0e-3;        // the buffer empty for this long -> safe state
  // Soft limits on the measured position [m] (the bridge's real-time thread checks them: beyond
  // either for kPositionLimitTicks ticks in a row, every axis goes to the safe state); none by default.
  double position_min_m = -std::numeric_limits<double>::infinity();
  double position_max_m = std::numeric_limits<double>::infinity();
  static constexpr int kPositionLimitTicks = 3;  // one noisy sample is no excursion

  void validate() const;  // throws ParameterError naming the field
  // The rate the safe state ramps at: safe_ramp_V_per_s, never faster than the slew limit.
  double safe_ramp_rate_V_per_s() const noexcept {
    return safe_ramp_V_per_s < slew_V_per_s ? safe_ramp_V_per_s : slew_V_per_s;
  }
  // The longest ramp to safe_u_V: from the end of the range farthest from it [s].
  double longest_safe_ramp_s() const noexcept {
    const double far_V = u_max_V - safe_u_V > safe_u_V - u_min_V ? u_max_V - safe_u_V : safe_u_V - u_min_V;
    return far_V / safe_ramp_rate_V_per_s();
  }
};

struct BridgeCounters {
  std::uint64_t ticks = 0;
  std::uint64_t applied = 0;     // armed ticks that applied a command meant for them
  std::uint64_t late = 0;        // armed ticks with no command for them (last feedforward held)
  std::uint64_t stale = 0;       // commands that arrived after their tick had passed
  std::uint64_t duplicates = 0;  // commands for a tick that had one already (the first stays)
  std::uint64_t rejected_nonfinite = 0;
  std::uint64_t rejected_future = 0;  // seq further ahead of the bridge's clock than max_lead_ticks
  std::uint64_t clamped = 0;          // armed ticks whose command was clamped to the range
  std::uint64_t slew_limited = 0;     // ... limited by the slew rate
  std::uint64_t clamped_either = 0;   // ... by either (a tick clamped by both counts once)
  std::uint64_t watchdog_trips = 0;
  std::uint64_t safe_ticks = 0;  // ticks in the safe state
};

// Armed ticks clamped during one whole second of loop time (BridgeCore::clamped_last_second).
struct ClampCounts {
  std::uint64_t either = 0;  // by the range or the slew limit (once when by both)
  std::uint64_t range = 0;
  std::uint64_t slew = 0;
};

struct BridgeTick {
  double u_applied_V = 0.0;
  double u_ff_V = 0.0;   // feedforward part (held when late; 0 in the safe state)
  double u_fb_V = 0.0;   // servo part (0 when off, held or without reference)
  double y_ref_m = 0.0;  // reference of the command in force; NaN = none
  std::int32_t flags = 0;
  std::int32_t params_version = 0;  // of the command in force (0 when none)
  std::int64_t buffer_depth = 0;    // consecutive ticks buffered after this one
};

class BridgeCore {
 public:
  // servo.u_min_V/u_max_V are taken from the actuator's range (the anti-windup limits).
  BridgeCore(const ActuatorLimits& limits, const FeedbackGains& servo, double dt_s = 1e-4);

  // A command received at any time before its tick. Returns false if refused (counted).
  bool submit(const CommandTick& command) noexcept;

  // The bridge owns its clock: a command for a tick more than `ticks` after the next one it
  // will take is refused (rejected_future), whatever the sensor stream the compensator planned
  // from said. 1 .. CommandBuffer::kCapacityTicks (the default: only the buffer's size bounds it).
  void set_max_lead_ticks(std::int64_t ticks);
  std::int64_t max_lead_ticks() const noexcept { return max_lead_ticks_; }

  // Decides the voltage for tick k (k increases between calls; a skipped tick is simply not
  // called). y_measured_m is the stage's position sampled at the end of the previous tick;
  // the servo acts on that tick's reference minus it.
  BridgeTick tick(std::int64_t k, double y_measured_m) noexcept;

  // Leave the safe state at tick k: commands are applied again, reached from the current
  // voltage under the slew limit; the watchdog counts from k. Disarm enters the safe state.
  void arm(std::int64_t k) noexcept;
  void disarm() noexcept;
  bool armed() const noexcept { return armed_; }
  // tick(k) would trip the watchdog (armed, no command for k, the buffer dry for too long): a
  // stage of several axes takes all of them to the safe state on the same tick (MultiAxisBridge).
  bool watchdog_due(std::int64_t k) const noexcept {
    return armed_ && !buffer_.has(k) && k - last_supplied_tick_ > watchdog_ticks_;
  }

  // New servo gains (validated by the caller: FeedbackGains::validate), bumplessly.
  void set_servo_gains(const FeedbackGains& gains) noexcept;
  const FeedbackGains& servo_gains() const noexcept { return servo_.gains(); }

  const BridgeCounters& counters() const noexcept { return counters_; }
  std::uint64_t watchdog_trips() const noexcept { return counters_.watchdog_trips; }
  // The clamped ticks of the last whole second of loop time: ticks [(s - 1) n, s n) while tick k
  // is in second s = floor(k / n), n = round(1 / dt) ticks per second (zero before the first).
  const ClampCounts& clamped_last_second() const noexcept { return clamp_last_second_; }
  const FeedbackController& servo() const noexcept { return servo_; }
  const ActuatorLimits& limits() const noexcept { return limits_; }
  double last_applied_V() const noexcept { return u_applied_; }
  std::int64_t buffer_depth() const noexcept { return buffer_.depth(); }

 private:
  ActuatorLimits limits_;
  double dt_s_;
  std::int64_t watchdog_ticks_;  // dry armed ticks allowed before the trip: floor(watchdog_s / dt)
  std::int64_t max_lead_ticks_ = CommandBuffer::kCapacityTicks;
  CommandBuffer buffer_;
  FeedbackController servo_;
  std::int64_t last_supplied_tick_ = 0;  // last armed tick whose command was in the buffer (or the arm tick)
  std::int64_t last_tick_ = -1;
  double u_applied_ = 0.0;  // last voltage applied (starts at the safe voltage)
  CommandTick held_{};      // command in force, held when one is late
  double servo_ref_m_;      // reference of the previous tick, for the servo's error (NaN: none)
  bool armed_ = false;
  bool command_since_arm_ = false;  // until then the servo neither acts nor forgets its held state
  bool safe_ramp_active_ = false;   // in the safe state: ramping from safe_ramp_from_V_ (or there)
  double safe_ramp_from_V_ = 0.0;
  std::int64_t safe_ramp_ticks_ = 0;  // safe-state ticks since the ramp started
  BridgeCounters counters_;
  std::int64_t ticks_per_second_;  // round(1 / dt), at least 1
  std::int64_t clamp_second_ = 0;  // the second of loop time clamp_this_second_ counts
  ClampCounts clamp_this_second_{};
  ClampCounts clamp_last_second_{};

  void roll_clamp_window(std::int64_t k) noexcept;
};

}  // namespace hystloop
