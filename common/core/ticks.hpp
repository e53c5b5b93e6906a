#pragma once
// One tick of the loop, as the bridge did it and as the compensator planned it: plain values
// shared by the loop's logic (common/loop), which knows no LCM, and the LCM blocks that carry
// them (common/lcm/blocks.hpp, sensor_block_t and command_block_t document each field).

#include <cstdint>

namespace hystloop {

// The largest tick number (sensor_block_t.seq, command_block_t.seq and sample_seq) a message may
// carry: seq + any horizon or block length then stays exact and far from the int64 ceiling.
inline constexpr std::int64_t kMaxTick = std::int64_t{1} << 53;  // 28,000 years at 10 kHz
// The most ticks one sensor or command block carries (their MAX_TICKS, checked in lcm/).
inline constexpr std::int64_t kMaxBlockTicks = 1000;

// What the bridge did at one tick.
struct SensorTick {
  std::int64_t utime = 0;  // [us]
  std::int64_t seq = 0;
  double u_V = 0.0;      // applied, after the clamp
  double u_ff_V = 0.0;   // feedforward part
  double u_fb_V = 0.0;   // servo part
  double y_ref_m = 0.0;  // NaN = no reference
  double y_m = 0.0;
  std::int32_t flags = 0;
};

// What the compensator planned for one tick.
struct CommandTick {
  std::int64_t seq = 0;
  double u_ff_V = 0.0;
  double y_ref_m = 0.0;  // NaN = no reference: the servo adds nothing
  std::int32_t params_version = 0;
  std::int8_t mode = 0;  // command_block_t.MODE_* / FeedforwardMode
};

}  // namespace hystloop
