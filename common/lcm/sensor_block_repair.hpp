#pragma once
// A sensor block the message contract refuses (lcm/message_checks.hpp: u, u_ff, u_fb and y finite
// and within the sanity bounds, y_ref finite or NaN, known flags, a buffer depth >= 0) would be
// dropped by the Publisher, and its ticks would be a hole in the record although the actuator
// moved through them. So before a block is published every value the contract refuses is
// replaced by one it allows, and the tick is flagged with the bit that says what the value is:
//
//   u_V                  clamped to +-kMaxAbsVoltage_V; NaN: the last good u_V     SATURATED
//   u_ff_V, u_fb_V       clamped to +-kMaxAbsVoltage_V; NaN: 0                      SATURATED
//   y_m                  the last good y_m (0 before any)                           SENSOR_FAULT
//   y_ref_m              NaN ("no reference") when infinite or beyond the bound
//   flags                bits the contract does not know cleared
//   buffer_depth_ticks   0 when negative
//
// SATURATED is true of such a tick anyway: a command beyond what any amplifier takes was clamped
// to the actuator's range. SENSOR_FAULT says "y_m is the last good value", which it then is, and
// makes the re-identifier skip the tick. Allocation-, lock- and throw-free: the I/O thread runs it
// on every block (it also keeps the last good values), the counts go to HX_STATUS.

#include <array>
#include <cstdint>

#include "hystloop/sensor_block_t.hpp"

namespace hystloop {

// What repair() replaced in one block, by kind (a tick counts once in `ticks`).
struct SensorRepair {
  std::int32_t ticks = 0;       // ticks with at least one value replaced
  std::int32_t voltages = 0;    // u_V, u_ff_V or u_fb_V values
  std::int32_t positions = 0;   // y_m values
  std::int32_t references = 0;  // y_ref_m values
  std::int32_t flag_words = 0;  // flags with unknown bits
  bool buffer_depth = false;    // a negative buffer depth
  bool any() const noexcept { return ticks > 0 || buffer_depth; }
};

class SensorBlockRepair {
 public:
  // Makes `block` pass check_message (given consistent arrays of 1..MAX_TICKS ticks, as the
  // bridge fills them), and remembers each axis's last good u and y for the next block. A tick
  // counts once in `ticks` whichever of its axes had values replaced.
  SensorRepair repair(sensor_block_t& block) noexcept;

 private:
  std::array<double, sensor_block_t::MAX_AXES> last_u_V_{};  // per axis
  std::array<double, sensor_block_t::MAX_AXES> last_y_m_{};
};

}  // namespace hystloop
