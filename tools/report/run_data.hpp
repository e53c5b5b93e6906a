#pragma once
// What hystloop-report keeps of an LCM event log: the fields the figures need, one
// record per logged message. Times are the log's event timestamps, i.e. the logger's
// RECEIVE times [us since the epoch], not the senders' utime fields: one clock for
// every channel, so sample-to-command latency can be taken from the log alone.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace hystloop::report {

struct SampleRecord {
  std::int64_t recv_utime = 0;
  std::int64_t seq = 0;
  double u_V = 0.0;
  double y_m = 0.0;
  std::int32_t flags = 0;
};

struct CommandRecord {
  std::int64_t recv_utime = 0;
  std::int64_t seq = 0;         // the tick it is meant for
  std::int64_t sample_seq = -1; // the sample it answers (-1: none)
  double u_V = 0.0;
  double y_ref_m = 0.0;         // NaN: no reference
  std::int32_t params_version = 0;
};

struct ParamsRecord {
  std::int64_t recv_utime = 0;
  std::int32_t version = 0;
  double c1 = 0.0, c2 = 0.0, c3 = 0.0;
  double residual_m = 0.0;
  bool valid = false;
};

struct StatusRecord {
  std::int64_t recv_utime = 0;
  std::string process;
  std::int8_t state = 0;
  std::int64_t late = 0;
  std::int64_t rejected = 0;
  std::vector<std::pair<std::string, std::int64_t>> counters;
};

struct RunData {
  std::vector<SampleRecord> samples;     // in log order
  std::vector<CommandRecord> commands;
  std::vector<ParamsRecord> params;
  std::vector<StatusRecord> statuses;
  std::map<std::string, std::uint64_t> channel_counts;  // every event of every channel
  std::uint64_t events = 0;
  std::uint64_t undecodable = 0;  // events on a known channel that failed to decode or validate
  std::optional<std::int64_t> first_event_utime;

  // Time zero of every t_s: the first HX_SENSOR event, else the first event.
  std::int64_t time_zero_utime() const noexcept {
    if (!samples.empty()) return samples.front().recv_utime;
    return first_event_utime.value_or(0);
  }
};

}  // namespace hystloop::report
