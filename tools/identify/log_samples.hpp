#pragma once
// Identification samples from LCM event logs: the ticks of one axis of the rig's HX_SENSOR
// sensor_block_t messages (common/lcm/blocks.hpp; x unless LogReadOptions::axis says another), from one or several
// files in the order given (a rotated recording is one record), into the same SampleTable the CSV reader makes: one
// sample per tick, u = u_V, y = y_m, and t = (seq - seq of the first tick) * dt, or from the tick's utime. The files
// are read and the messages decoded by hystloop-report's reader (tools/report/event_file.hpp, decode.hpp), so both
// tools see the same events in a log.
//
// What a recording may hold and what becomes of it:
//  - ticks flagged SAFE_STATE (the bridge holding the safe voltage, not the experiment) or
//    SENSOR_FAULT (y_m is a stale value): skipped and counted;
//  - missing ticks (seq jumps): counted; they split nothing (MEM is rate independent, the
//    record simply continues), but the report says how many samples were lost;
//  - a tick again that the previous block held (the same block logged twice): the repeat is
//    skipped and counted;
//  - seq going back (files out of order, or the bridge restarted): refused, the message names
//    the file and event;
//  - a non-finite u or y: refused like a malformed CSV field, naming file, event and seq;
//  - an event on the sensor channel that does not decode as sensor_block_t, or whose values
//    break the message contract (range, flag bits, array sizes): skipped whole and counted;
//  - bytes that are not a complete event (a torn write): passed over, reading goes on at the
//    next event;
//  - other channels: ignored.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "hystloop/sensor_block_t.hpp"
#include "ident/sample_csv.hpp"

namespace hystloop {

// A log that cannot be used; the message names the file (and event).
class SampleLogError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws SampleLogError unless `block` carries `axis`: "<where>: its blocks carry 1 axis (x), not y".
void require_axis_in(const sensor_block_t& block, int axis, const std::string& where);

enum class LogTimeBase { seq, utime };

struct LogReadOptions {
  std::string sensor_channel = "HX_SENSOR";  // rig prefix + "SENSOR"
  LogTimeBase time_base = LogTimeBase::seq;
  double dt_s = 1e-4;  // tick period with LogTimeBase::seq [s]
  // Time range [from, to) relative to the first sample of the record [s]; empty = open.
  std::optional<double> from_s;
  std::optional<double> to_s;
  // The axis whose samples are read (0 x, 1 y, 2 z): blocks carry every axis of the stage. A block
  // without it (a one-axis record read for y) is refused, naming the axes it has.
  int axis = 0;

  // Throws ParameterError naming the field ("dt", "from", "to", "axis").
  void validate() const;
};

struct SeqGap {
  std::int64_t first_missing = 0;  // seq of the first missing tick
  std::size_t missing = 0;         // ticks missing from there
};

struct LogSamples {
  SampleTable table;  // the samples kept (t relative to the record's first sample)
  std::size_t files = 0;
  std::size_t events = 0;                           // events of any channel read
  std::size_t sensor_events = 0;                    // events (blocks) on the sensor channel
  std::size_t sensor_ticks = 0;                     // ticks of the blocks that decoded and met the contract
  std::size_t outside_range = 0;                    // valid ticks outside [from, to)
  std::size_t safe_state = 0;                       // skipped ticks: flagged SAFE_STATE
  std::size_t sensor_fault = 0;                     // skipped ticks: flagged SENSOR_FAULT (and not SAFE_STATE)
  std::size_t duplicates = 0;                       // skipped ticks: the same seq again
  std::size_t undecodable = 0;                      // skipped events: not a sensor_block_t, or out of contract
  std::vector<std::string> signature_notes;         // for_each_log_event's
  std::size_t gaps = 0;                             // seq jumps among the samples in range
  std::size_t missing = 0;                          // ticks missing in those jumps
  std::vector<SeqGap> first_gaps;                   // the first few, for the report
  std::optional<std::int64_t> first_seq, last_seq;  // of the samples kept

  double window_s() const noexcept { return table.t.size() < 2 ? 0.0 : table.t.back() - table.t.front(); }
  // Ticks skipped (the undecodable events are counted apart).
  std::size_t skipped() const noexcept { return safe_state + sensor_fault + duplicates; }
};

// Calls on_event(file, event) for every event of the files, in order. Throws SampleLogError for
// a file that is not there or does not open as an LCM event log. With the process's rig key
// (--key-file) an event on a signed channel whose signature fails is left out; returns what to
// tell the user about signatures, per file ("run.000.lcmlog: 3 message(s) failed signature
// verification and were left out (...)", or that a keyed log was read unverified).
std::vector<std::string> for_each_log_event(
    const std::vector<std::string>& files,
    const std::function<void(const std::string& file, const lcm::LogEvent& event)>& on_event);

// True for a path that names an LCM event log by its ending (".lcmlog").
bool looks_like_lcm_log(const std::string& path);

// Reads the files in order as one record. Throws SampleLogError for a file that cannot be
// opened, a non-finite value, seq going back, or no sample left; ParameterError for bad options.
LogSamples read_sample_logs(const std::vector<std::string>& files, const LogReadOptions& options);

// Lines for the tool's report: counts of what was kept, skipped and missing.
std::string describe(const LogSamples& samples, const LogReadOptions& options);

}  // namespace hystloop
