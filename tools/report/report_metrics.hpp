#pragma once
// The figures of a recorded run, computed from RunData alone (no I/O), so that each can
// be checked against an independent computation in a test.
//
// Time axis: t_s = (time of a tick or event - time of the first HX_SENSOR tick) [s], both on
// the log's receive clock (run_data.hpp dates the ticks of a block).
// Tracking error of tick k: e_k = y_ref_k - y_k, both as the bridge recorded them in HX_SENSOR;
// only ticks with a finite y_ref count ("tracking").
// Run-ahead margin of a command block: block.seq - sample_seq [ticks], how far ahead of the
// newest sensor tick the compensator knew its first new command was (blocks with sample_seq
// -1 are left out).
// Armed: a tick without SAFE_STATE; a sensor block with no SAFE_STATE tick.
// Percentiles are nearest-rank: the ceil(q*n)-th smallest value.

#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "run_data.hpp"

namespace hystloop::report {

struct ReportOptions {
  std::optional<double> from_s;  // keep t_s >= from_s (+ skip_initial_s)
  std::optional<double> to_s;    // keep t_s <= to_s
  double skip_initial_s = 0.0;   // warm-up excluded at the start of the range, >= 0
  std::string bridge_process = "bridge";
  std::string logger_process = "logger";

  // Throws ParameterError naming the option ("--from", "--to", "--skip-initial").
  void validate() const;
  // The selected interval [lower, upper] of t_s (lower = -inf without --from/--skip-initial).
  double lower_s() const noexcept;
  double upper_s() const noexcept;
};

struct SecondBin {
  double t_s = 0.0;  // start of the one-second bin
  std::size_t tracking_samples = 0;
  std::optional<double> rms_error_m;
  std::int32_t params_version = 0;  // of the last command applied in the bin (carried forward)
  std::size_t clamped_samples = 0;  // ticks clamped by the range or the slew limit (once when by both)
};

struct MemParams {
  std::int32_t version = 0;
  double c1 = 0.0, c2 = 0.0, c3 = 0.0;
};

// One published parameter set (HX_PARAMS or HX_MODEL) in the range.
struct ParamsPoint {
  double t_s = 0.0;
  std::int32_t version = 0;
  double c1 = 0.0, c2 = 0.0, c3 = 0.0, residual_m = 0.0;  // c1..c3 NaN unless the model is MEM
  bool valid = false;
  std::string model = "mem";
  double heldout_rms_m = 0.0;  // NaN: not given
  bool model_change = false;   // from HX_MODEL: the feedforward switched to this model
};

// The compensator began applying another parameter version: the first sensor tick whose command
// was computed with `to` (the tick after the last one with `from`).
struct ParamsSwap {
  double t_s = 0.0;
  std::int64_t seq = 0;
  std::int32_t from = 0, to = 0;
};

struct ReportMetrics {
  int axis = 0;             // whose ticks every figure is of (RunData::axis)
  int log_axes = 0;         // the most axes a sensor block of the log carries; 0: no block
  std::size_t samples = 0;  // sensor samples in the range
  double duration_s = 0.0;  // last minus first sample time in the range
  std::optional<double> first_sample_t_s, last_sample_t_s;

  std::size_t tracking_samples = 0;
  std::optional<double> rms_error_m, max_abs_error_m;
  std::optional<double> rms_error_first_5s_m, rms_error_last_5s_m;
  std::vector<SecondBin> per_second;

  std::size_t armed_samples = 0;                // ticks without SAFE_STATE
  std::size_t late_samples = 0;                 // armed ticks with LATE_COMMAND
  std::optional<double> late_command_fraction;  // late / armed ticks (summary: also late_tick_fraction)

  // Ticks the bridge clamped, from their flags: SATURATED (to the range), SLEW_LIMITED, and
  // either (a tick clamped by both counts once); per second in per_second.
  std::size_t clamped_range_samples = 0;
  std::size_t clamped_slew_samples = 0;
  std::size_t clamped_samples = 0;

  std::size_t sensor_blocks = 0;  // HX_SENSOR blocks in the range
  std::size_t armed_blocks = 0;
  std::optional<std::int32_t> buffer_min_depth_ticks;  // lowest buffer_depth_ticks of an armed block
  std::optional<double> tick_period_s;                 // dt_s of the first sensor block in the range

  std::vector<double> run_ahead_ticks;  // per command block in the range, sorted ascending
  std::optional<double> run_ahead_min_ticks, run_ahead_p01_ticks, run_ahead_p50_ticks, run_ahead_max_ticks;

  std::optional<std::int64_t> watchdog_trips;
  std::string watchdog_trips_source;  // the bridge counter, or the SAFE_STATE transitions counted

  std::map<std::string, std::optional<double>> messages_per_s;  // events in the sampled span / duration_s
  std::map<std::string, std::optional<double>> cpu_fraction;    // per process [cores], from its HX_STATUS

  std::optional<std::int64_t> commands_rejected;
  std::string commands_rejected_source;  // which counters of which status, or why none
  std::vector<std::pair<std::string, std::int64_t>> commands_rejected_counters;

  std::vector<ParamsPoint> params_history;  // in the range, one entry per (version, valid)
  std::vector<ParamsSwap> swaps;            // in the range, in time order
  std::optional<MemParams> params_initial, params_final;
  std::size_t params_updates = 0;

  std::optional<std::int64_t> logger_gaps;
  std::string logger_gaps_source;    // "logger status counter <name>" or "sensor seq"
  std::int64_t seq_gaps = 0;         // jumps > 1 between consecutive samples in the range
  std::int64_t missing_samples = 0;  // ticks missing in those jumps

  std::map<std::string, std::uint64_t> channels;
  std::uint64_t events = 0;
  std::uint64_t undecodable = 0;
  // Signatures (record/record_auth.hpp): read with the rig's key; events left out because their
  // signature failed; a file of the log says it was recorded on a keyed rig.
  bool signatures_verified = false;
  std::uint64_t unverified_left_out = 0;
  bool recorded_keyed = false;
};

ReportMetrics compute_metrics(const RunData& run, const ReportOptions& options);

// Nearest-rank percentile of an ascending vector, q in [0, 1]; nullopt when empty.
std::optional<double> nearest_rank(const std::vector<double>& sorted, double q) noexcept;

// The RMS of the errors added; nullopt when none was.
struct RmsSum {
  double sum_sq = 0.0;
  std::size_t n = 0;
  void add(double e) noexcept {
    sum_sq += e * e;
    ++n;
  }
  std::optional<double> rms() const noexcept {
    return n == 0 ? std::nullopt : std::optional<double>(std::sqrt(sum_sq / static_cast<double>(n)));
  }
};

// One tick (for plots): time, applied voltage, measured and reference position, and what the
// compensator commanded it with.
struct TrackPoint {
  double t_s;
  double u_V;
  double y_m;
  double y_ref_m;                                   // NaN when the tick had no reference
  std::int8_t mode = VersionRun::kUnknownMode;      // command_block_t::MODE_* of its command
  std::optional<std::int32_t> params_version = {};  // of its command; none when no command was logged
  bool armed = true;                                // no SAFE_STATE
};
// Every sensor tick of the range, in log order.
std::vector<TrackPoint> track_points(const RunData& run, const ReportOptions& options);

}  // namespace hystloop::report
