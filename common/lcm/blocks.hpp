#pragma once
// One tick of an HX_SENSOR or HX_COMMAND block, and the only place that knows how a block's
// arrays map to ticks. Services build blocks tick by tick into a message whose storage was
// reserved (reserve_storage), so appending allocates nothing; tools that work per tick
// (logger, report, identification, replay) walk a block with for_each_tick.

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "core/ticks.hpp"
#include "hystloop/command_block_t.hpp"
#include "hystloop/sensor_block_t.hpp"

namespace hystloop {

// Tick i of a block whose arrays are consistent (check_message / arrays_consistent).
inline SensorTick sensor_tick(const sensor_block_t& b, std::size_t i) noexcept {
  const double offset_us = static_cast<double>(i) * b.dt_s * 1e6;
  return {b.utime + static_cast<std::int64_t>(std::llround(offset_us)),
          b.seq + static_cast<std::int64_t>(i),
          b.u_V[i],
          b.u_ff_V[i],
          b.u_fb_V[i],
          b.y_ref_m[i],
          b.y_m[i],
          b.flags[i]};
}

inline CommandTick command_tick(const command_block_t& b, std::size_t i) noexcept {
  return {b.seq + static_cast<std::int64_t>(i), b.u_ff_V[i], b.y_ref_m[i], b.params_version[i], b.mode[i]};
}

// Calls fn(tick) for every tick of the block, in order.
template <class Fn>
void for_each_tick(const sensor_block_t& b, Fn&& fn) {
  for (std::size_t i = 0; i < b.u_V.size(); ++i) fn(sensor_tick(b, i));
}
template <class Fn>
void for_each_tick(const command_block_t& b, Fn&& fn) {
  for (std::size_t i = 0; i < b.u_ff_V.size(); ++i) fn(command_tick(b, i));
}

// Last tick a block covers (seq + n_ticks - 1).
inline std::int64_t last_seq(const sensor_block_t& b) noexcept { return b.seq + b.n_ticks - 1; }
inline std::int64_t last_seq(const command_block_t& b) noexcept { return b.seq + b.n_ticks - 1; }

// Empties a block to be filled from tick `seq` on (keeps the reserved capacity).
void begin_block(sensor_block_t& b, std::int64_t seq, std::int64_t utime, double dt_s) noexcept;
void begin_block(command_block_t& b, std::int64_t seq, std::int64_t utime, std::int64_t sample_seq) noexcept;

// Appends the next tick; returns false (and appends nothing) when the block already holds
// MAX_TICKS. Allocation-free on a message prepared with reserve_storage. The tick's seq and
// utime are implied by the block's and are not checked.
bool append_tick(sensor_block_t& b, const SensorTick& t) noexcept;
bool append_tick(command_block_t& b, const CommandTick& t) noexcept;

}  // namespace hystloop
