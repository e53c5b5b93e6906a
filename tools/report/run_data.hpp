#pragma once
// What hystloop-report keeps of an LCM event log: the fields the figures need. Times are the
// log's event timestamps, i.e. the logger's RECEIVE times [us since the epoch], not the
// senders' utime fields: one clock for every channel.
//
// HX_SENSOR and HX_COMMAND carry blocks of ticks (common/lcm/blocks.hpp). A sensor block is
// received after its last tick was sampled, so tick i of a block of n received at time R is
// dated R - (n - 1 - i) * dt_s: the last tick at the receive time, the others a tick period
// apart before it. Command ticks are planned ahead of the clock and keep only what the figures
// need: the parameter version each tick was computed with.

#include <algorithm>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace hystloop::report {

// One tick of HX_SENSOR.
struct SampleRecord {
  std::int64_t recv_utime = 0;  // the block's receive time, back-dated to this tick (above)
  std::int64_t seq = 0;
  double u_V = 0.0;
  double y_ref_m = 0.0;  // NaN: no reference
  double y_m = 0.0;
  std::int32_t flags = 0;
  // The simulated stage's true position at this tick (HX_SIM_TRUTH); NaN: none (hardware, or
  // its truth block was not in the log).
  double y_true_m = std::numeric_limits<double>::quiet_NaN();
};

// One HX_SENSOR block (its ticks are in RunData::samples).
struct SensorBlockRecord {
  std::int64_t recv_utime = 0;
  double dt_s = 0.0;
  std::int32_t buffer_depth_ticks = 0;
  bool armed = false;  // no tick of the block is SAFE_STATE
};

// One HX_COMMAND block.
struct CommandBlockRecord {
  std::int64_t recv_utime = 0;
  std::int64_t seq = 0;          // first tick it plans
  std::int64_t sample_seq = -1;  // last sensor tick the compensator had (-1: none)
};

// params_version and mode of the command ticks [first_seq, end_seq): consecutive ticks with one
// version and one mode.
struct VersionRun {
  std::int64_t first_seq = 0;
  std::int64_t end_seq = 0;
  std::int32_t version = 0;
  std::int8_t mode = kUnknownMode;  // command_block_t::MODE_*

  static constexpr std::int8_t kUnknownMode = -1;
};

// The parameter version and mode each commanded tick was computed with. A tick is normally sent once;
// a command tick at or before the highest one already logged is a re-send and is ignored (the
// first logged command for a tick is the one the bridge used).
class CommandVersions {
 public:
  void add(std::int64_t seq, std::int32_t version, std::int8_t mode = VersionRun::kUnknownMode);
  // The version of tick `seq`, if a command for it was logged.
  std::optional<std::int32_t> at(std::int64_t seq) const noexcept;
  // The run holding tick `seq` (its version and mode), nullptr if no command for it was logged.
  const VersionRun* run_at(std::int64_t seq) const noexcept;
  const std::vector<VersionRun>& runs() const noexcept { return runs_; }

 private:
  std::vector<VersionRun> runs_;  // increasing, disjoint
};

// A parameter set: HX_PARAMS (MEM) or HX_MODEL (any model; c1..c3 only when it is MEM).
struct ParamsRecord {
  std::int64_t recv_utime = 0;
  std::int32_t version = 0;
  double c1 = 0.0, c2 = 0.0, c3 = 0.0;
  double residual_m = 0.0;
  bool valid = false;
  std::string model = "mem";   // ModelKind's name
  double heldout_rms_m = 0.0;  // NaN: not given (HX_PARAMS' residual_m is its held-out RMS)
  bool model_channel = false;  // from HX_MODEL: a model change (the feedforward switched to it)
};

struct StatusRecord {
  std::int64_t recv_utime = 0;
  std::string process;
  std::int64_t rejected = 0;
  std::vector<std::pair<std::string, std::int64_t>> counters;
  std::int64_t utime = 0;        // the sender's time of the report [us]
  std::int64_t start_utime = 0;  // the sender's start [us]

  std::optional<std::int64_t> counter(const std::string& name) const {
    const auto it = std::find_if(counters.begin(), counters.end(), [&](const auto& c) { return c.first == name; });
    return it == counters.end() ? std::nullopt : std::optional<std::int64_t>(it->second);
  }
};

// A DISARM or SHUTDOWN request on HX_CONTROL (what puts a bridge in the safe state on purpose).
struct SafeRequestRecord {
  std::int64_t recv_utime = 0;
  std::string target;  // empty: every process
};

// What the event-log layer made of one file. lcm's reader skips bytes silently while it looks
// for the next event's sync word and stops at the first event it cannot read whole, so a torn
// write, a truncated tail or a file of random bytes would otherwise pass unnoticed.
struct LogFileScan {
  std::string file;
  std::uint64_t bytes = 0;           // file size
  std::uint64_t events = 0;          // complete events read
  std::uint64_t skipped_bytes = 0;   // bytes before or between events that were not an event
  std::uint64_t trailing_bytes = 0;  // bytes after the last complete event (truncated, or junk)
  // Signatures (record/record_auth.hpp): the file starts as a keyed rig's logger writes it; events
  // left out because their signature failed (only when a key was given); what to tell the user.
  bool recorded_keyed = false;
  std::uint64_t unverified_left_out = 0;
  std::vector<std::string> signature_notes;
  bool clean() const noexcept { return bytes > 0 && skipped_bytes == 0 && trailing_bytes == 0; }
};

struct RunData {
  // The axis the ticks below are of (0 x, 1 y, 2 z: hystloop-report --axis): a sensor block carries
  // every axis of the stage on one clock (common/lcm/blocks.hpp); commands, truth and parameter
  // sets are read for this axis too.
  int axis = 0;
  std::map<int, std::uint64_t> sensor_blocks_by_axes;  // HX_SENSOR blocks by their n_axes
  std::uint64_t blocks_without_axis = 0;               // HX_SENSOR blocks that lack `axis`: left out whole
  std::vector<SampleRecord> samples;                   // every tick of `axis`, in log order
  std::vector<SensorBlockRecord> sensor_blocks;
  std::vector<CommandBlockRecord> command_blocks;
  CommandVersions command_versions;
  std::vector<ParamsRecord> params;
  std::vector<StatusRecord> statuses;
  std::vector<SafeRequestRecord> safe_requests;
  std::uint64_t truth_ticks = 0;                                 // samples given a true position from HX_SIM_TRUTH
  std::map<std::string, std::uint64_t> channel_counts;           // every event of every channel
  std::map<std::string, std::vector<std::int64_t>> event_times;  // receive time of every event, by channel
  std::uint64_t events = 0;
  std::uint64_t undecodable = 0;     // events on a known channel that failed to decode or validate
  bool signatures_verified = false;  // read with the rig's key: LogFileScan::unverified_left_out were left out
  std::optional<std::int64_t> first_event_utime;
  std::vector<LogFileScan> files;  // one per file read, in order

  // Time zero of every t_s: the first HX_SENSOR tick, else the first event.
  std::int64_t time_zero_utime() const noexcept {
    if (!samples.empty()) return samples.front().recv_utime;
    return first_event_utime.value_or(0);
  }
  // The report's time axis: seconds of a receive time after time_zero_utime().
  double t_s(std::int64_t utime) const noexcept { return static_cast<double>(utime - time_zero_utime()) * 1e-6; }
};

}  // namespace hystloop::report
