#pragma once
// One tick of an HX_SENSOR or HX_COMMAND block, and the only place that knows how a block's
// arrays map to ticks. Services build blocks tick by tick into a message whose storage was
// reserved (reserve_storage), so appending allocates nothing; tools that work per tick
// (logger, report, identification, replay) walk a block with for_each_tick.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/ticks.hpp"
#include "hystloop/command_block_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/sim_truth_t.hpp"

namespace hystloop {

// A block's axes and ticks: its arrays hold n_ticks x n_axes values, tick-major (tick i of axis a
// at i * n_axes + a). An n_axes outside 1..MAX_AXES reads as 1 here (check_message refuses such a
// block before anything walks it).
inline std::size_t axes_of(std::int8_t n_axes) noexcept {
  return n_axes >= 1 && n_axes <= sensor_block_t::MAX_AXES ? static_cast<std::size_t>(n_axes) : 1;
}
inline std::size_t axes_of(const sensor_block_t& b) noexcept { return axes_of(b.n_axes); }
inline std::size_t axes_of(const command_block_t& b) noexcept { return axes_of(b.n_axes); }
inline std::size_t ticks_of(const sensor_block_t& b) noexcept { return b.u_V.size() / axes_of(b); }
inline std::size_t ticks_of(const command_block_t& b) noexcept { return b.u_ff_V.size() / axes_of(b); }
inline std::size_t axes_of(const sim_truth_t& b) noexcept { return axes_of(b.n_axes); }
inline std::size_t ticks_of(const sim_truth_t& b) noexcept { return b.y_true_m.size() / axes_of(b); }

// Tick i of `axis` (0: x, the only one of a one-axis block) of a block whose arrays are consistent
// (check_message / arrays_consistent) and axis < n_axes.
inline SensorTick sensor_tick(const sensor_block_t& b, std::size_t i, std::size_t axis = 0) noexcept {
  const double offset_us = static_cast<double>(i) * b.dt_s * 1e6;
  const std::size_t v = i * axes_of(b) + axis;
  return {b.utime + static_cast<std::int64_t>(std::llround(offset_us)),
          b.seq + static_cast<std::int64_t>(i),
          b.u_V[v],
          b.u_ff_V[v],
          b.u_fb_V[v],
          b.y_ref_m[v],
          b.y_m[v],
          b.flags[v]};
}

inline CommandTick command_tick(const command_block_t& b, std::size_t i, std::size_t axis = 0) noexcept {
  const std::size_t v = i * axes_of(b) + axis;
  return {b.seq + static_cast<std::int64_t>(i), b.u_ff_V[v], b.y_ref_m[v], b.params_version[v], b.mode[v]};
}

// Calls fn(tick) for every tick of the block's `axis` (x by default), in order.
template <class Fn>
void for_each_tick(const sensor_block_t& b, Fn&& fn, std::size_t axis = 0) {
  for (std::size_t i = 0, n = ticks_of(b); i < n; ++i) fn(sensor_tick(b, i, axis));
}
template <class Fn>
void for_each_tick(const command_block_t& b, Fn&& fn, std::size_t axis = 0) {
  for (std::size_t i = 0, n = ticks_of(b); i < n; ++i) fn(command_tick(b, i, axis));
}

// One axis's true positions of a truth block, tick by tick (for tools: allocates); empty when the
// block lacks the axis.
std::vector<double> axis_truth(const sim_truth_t& b, std::size_t axis = 0);

// Last tick a block covers (seq + n_ticks - 1).
inline std::int64_t last_seq(const sensor_block_t& b) noexcept { return b.seq + b.n_ticks - 1; }
inline std::int64_t last_seq(const command_block_t& b) noexcept { return b.seq + b.n_ticks - 1; }

// Empties a block of `axes` axes (1..MAX_AXES) to be filled from tick `seq` on (keeps the reserved
// capacity).
void begin_block(sensor_block_t& b, std::int64_t seq, std::int64_t utime, double dt_s, int axes = 1) noexcept;
void begin_block(command_block_t& b, std::int64_t seq, std::int64_t utime, std::int64_t sample_seq,
                 int axes = 1) noexcept;

// Appends the next tick of a one-axis block; returns false (and appends nothing) when the block
// already holds MAX_TICKS or has more than one axis. Allocation-free on a message prepared with
// reserve_storage. The tick's seq and utime are implied by the block's and are not checked.
bool append_tick(sensor_block_t& b, const SensorTick& t) noexcept;
bool append_tick(command_block_t& b, const CommandTick& t) noexcept;
// A truth block for the ticks of a sensor block of `axes` axes from tick `seq` (storage kept).
void begin_block(sim_truth_t& b, std::int64_t seq, std::int64_t utime, int axes = 1) noexcept;
// The next tick's true position of every axis (exactly n_axes of them, else false, nothing appended).
bool append_tick(sim_truth_t& b, std::span<const double> y_true_m) noexcept;

// The next tick of every axis: ticks[a] is axis a's, exactly n_axes of them (else false, nothing
// appended).
bool append_tick(sensor_block_t& b, std::span<const SensorTick> ticks) noexcept;
bool append_tick(command_block_t& b, std::span<const CommandTick> ticks) noexcept;

}  // namespace hystloop
