#pragma once
// The value contract of every message type: what a receiver accepts and a publisher may
// send. Non-finite values are told apart from out-of-range ones so that the counts say
// which kind of sender bug it is. The bounds are sanity bounds (unit mistakes, corrupted
// senders), not the actuator's limits: the bridge clamps to those itself.
// String fields must hold no NUL (it would be cut when the message is encoded again), and tick
// numbers stay below 2^53 (seq + a horizon is then exact). All checks are allocation- and
// throw-free (they run at 10 kHz).

#include <cstdint>

#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/model_params_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/scan_t.hpp"
#include "hystloop/sim_truth_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "core/ticks.hpp"
#include "lcm/reject_reason.hpp"

namespace hystloop {

inline constexpr double kMaxAbsVoltage_V = 1.0e4;  // no piezo amplifier goes near 10 kV
inline constexpr double kMaxAbsPosition_m = 1.0;   // a nanopositioner moves micrometres
inline constexpr double kMaxAbsFrequency_Hz = 1.0e5;
inline constexpr double kMaxDuration_s = 86400.0;
inline constexpr std::int32_t kKnownSampleFlags = 63;       // SATURATED .. SENSOR_FAULT
inline constexpr int kWireAxes = sensor_block_t::MAX_AXES;  // axes a message may name: 0 (x) .. kWireAxes - 1
static_assert(kMaxBlockTicks == sensor_block_t::MAX_TICKS && kMaxBlockTicks == command_block_t::MAX_TICKS,
              "core/ticks.hpp's block bound is the wire's");

// sensor_block_t: 1..MAX_TICKS ticks of 1..MAX_AXES axes with every array of n_values = n_ticks x
// n_axes; per tick and axis finite u, u_ff, u_fb and y within the sanity bounds, y_ref finite or NaN (none), known
// flags; seq, utime and buffer depth >= 0, 0 < dt_s <= 1 s.
Verdict check_message(const sensor_block_t& msg) noexcept;
// sim_truth_t: 1..MAX_TICKS ticks of 1..MAX_AXES axes with the array of n_values = n_ticks x n_axes,
// each within the position bound; seq and utime >= 0.
Verdict check_message(const sim_truth_t& msg) noexcept;
// command_block_t: 1..MAX_TICKS ticks of 1..MAX_AXES axes with every array of n_values = n_ticks x
// n_axes; per tick and axis finite u_ff,
// y_ref finite or NaN (no reference), params_version >= 0, a known mode; seq >= 0,
// sample_seq >= -1, utime >= 0.
Verdict check_message(const command_block_t& msg) noexcept;
// trajectory_t: known shape, finite numbers, frequency > 0 for periodic shapes, version >= 1,
// 0..MAX_POINTS points (>= 1 for POINTS) with strictly increasing times >= 0, array sizes
// equal to n_points (so that encoding never reads past a vector).
Verdict check_message(const trajectory_t& msg) noexcept;
// mem_params_t: finite, c1 > 0, c2 >= 0, 0 < c3 <= 50, residual, samples and window >= 0,
// version >= 1. Validity (`valid`) is the consumer's decision, not a wire error; so is
// publisher_id (any value names a publisher, 0 = unknown).
Verdict check_message(const mem_params_t& msg) noexcept;
// model_params_t: the envelope (check_model_params_envelope), format_version FORMAT_VERSION and a
// known kind. What a Publisher sends and a receiver without its own reasons refuses.
Verdict check_message(const model_params_t& msg) noexcept;
// model_params_t without the two "not understood" fields: utime, samples and window >= 0,
// version >= 1, every number finite (heldout_rms_m may be NaN = not ranked), n_operators
// 0..MAX_OPERATORS with both arrays that long, no NUL in source; and for a known kind its
// parameters' ranges: MEM as mem_params_t; PI n_operators >= 1, r_0 = 0, thresholds increasing,
// w_0 > 0; linear gain != 0; Katalenic k1, k2 > 0 and known shaping kinds. A receiver that counts
// an unknown kind or format by its own reason subscribes with this one (ModelParamSet::validate
// then checks the rest, e.g. every cumulative PI weight > 0).
Verdict check_model_params_envelope(const model_params_t& msg) noexcept;

// service_status_t: non-empty process, pid > 0, known state, 0..MAX_COUNTERS counters >= 0
// with matching array sizes, timings NaN (not measured) or finite >= 0.
Verdict check_message(const service_status_t& msg) noexcept;
// trajectory_t, mem_params_t, model_params_t and control_t name an axis: 0..kWireAxes-1.
// control_t: known command and mode, request_id > 0, gains and notch NaN (keep) or finite >= 0; START_EXPERIMENT
// needs a name and amplitude, frequency and duration > 0.
Verdict check_message(const control_t& msg) noexcept;

// scan_t: a known path, finite numbers within the position, frequency and duration bounds, version
// >= 1; a raster's two different axes, known slow mode, width and line rate > 0 and 2..4096 lines; a
// Lissajous figure's duration > 0. (Whether the stage has those axes, and whether the actuator can
// follow, is the compensator's check.)
Verdict check_message(const scan_t& msg) noexcept;

// The check a Subscription/Publisher uses; the default is check_message for T.
template <class T>
using MessageCheck = Verdict (*)(const T&) noexcept;

template <class T>
constexpr MessageCheck<T> default_message_check() noexcept {
  return static_cast<MessageCheck<T>>(&check_message);
}

}  // namespace hystloop
