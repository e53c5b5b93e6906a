#pragma once
// What a recording did, written at close: a JSON file next to the logs for scripts, and
// a few lines for the process log. Built once, after the disk thread has stopped.
//
// JSON layout (counts are integers; times in us since the epoch; durations in s):
//   { "recording", "keyed", "start_utime", "stop_utime", "duration_s", "stop_reason",
//     "files": [ {"path", "events", "bytes"} ],
//     "totals": { "received", "written", "dropped", "bytes_written", "gap_events", "missing", "skipped",
//                 "contract_violations" },
//     "dropped": { "queue_full", "oversize", "write_failed", "unrecorded_channel" },
//     "disk": { "ok", "errors", "last_error", "events_lost", "files_truncated", "files_removed",
//               "unconfirmed_events", "recoveries" },
//     "unknown_channels": { "messages", "distinct", "distinct_is_lower_bound", "first": [names] },
//     "queue": { "capacity_bytes", "high_water_bytes" },
//     "process": { "cpu_user_s", "cpu_system_s", "peak_rss_bytes" },
//     "channels": { "<name>": { "received", "bytes_received", "written", "bytes_written",
//                               "dropped", "dropped_queue_full", "dropped_oversize", "write_failed",
//                               ["refused": { "unsigned", "malformed", "bad_mac", "replayed", "skewed" }],
//                               ["sequence": { "blocks", "ticks", "first_seq", "last_seq", "gap_events", "missing",
//                                              "resumes", "skipped", "overlaps", "overlap_ticks",
//                                              "duplicates", "out_of_order", "restarts", "undecodable",
//                                              "contract_violations": { "negative_seq", "seq_above_max",
//                                                                       "tick_count" },
//                                              "gaps": [[first_missing, last_missing], ...] }] } } }
// Counts in "sequence" are of blocks, except ticks, missing, skipped and overlap_ticks (ticks);
// first_seq/last_seq are tick numbers; "contract_violations" counts blocks whose seq or n_ticks
// the channel contract forbids, by reason (not checked for gaps: SequenceGapDetector). Every
// count and total saturates at UINT64_MAX. "gaps" lists the first SequenceGapDetector::kKeptGaps
// gaps of a channel; "sequence" is present for the channels checked for gaps (the rig's
// sensor and command channels). "disk.ok" is false after any disk fault (LogFileSet): then
// "events_lost" events were not written (also in dropped.write_failed) and the process exits 1.
// "refused" (a keyed rig's signed channels) counts the messages whose signature failed: counted
// in "received", never recorded. "unknown_channels" are the channels the table had no slot for (UnknownChannels).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "record/channel_table.hpp"
#include "logger/log_file_set.hpp"

namespace hystloop {

struct RecordingSummary {
  std::string recording;  // the recording's base path
  std::int64_t start_utime = 0;
  std::int64_t stop_utime = 0;
  double duration_s = 0.0;
  std::string stop_reason;
  std::vector<LogFileInfo> files;
  DiskFaults disk;
  std::uint64_t unrecorded_channel = 0;  // messages of channels the table had no room for
  bool keyed = false;                    // signatures verified (record/record_auth.hpp)
  std::uint64_t queue_capacity_bytes = 0;
  std::uint64_t queue_high_water_bytes = 0;
  double cpu_user_s = 0.0;  // the whole process, all threads
  double cpu_system_s = 0.0;
  std::int64_t peak_rss_bytes = 0;
};

// The summary as JSON text (runtime/summary_file.hpp: write it with write_file_atomically).
std::string summary_json(const RecordingSummary& summary, const ChannelTable& channels);

// A few lines: files, per-channel counts, gaps and drops.
std::vector<std::string> summary_lines(const RecordingSummary& summary, const ChannelTable& channels);

}  // namespace hystloop
