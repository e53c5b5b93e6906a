#pragma once
// The inputs of a recorded compensator, as a log to play back into a fresh one: its input
// channels (SENSOR, TRAJECTORY, PARAMS, CONTROL) and nothing else, from the point where the
// recorded compensator was running.
//
// Warm-up: the original may have started after the log did. Sensor blocks are kept from the
// first one it answered: the block holding the first answered sample, the lowest sample_seq
// (>= 0) among its command blocks (sample_seq is the last sensor tick it had). Other inputs
// logged before that block are kept only if they arrived after the compensator started
// (start_utime of its first HX_STATUS, when the log holds one; compared with the log's
// receive timestamps). A sensor block is "answered" when a command block's sample_seq lies
// in it.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "lcm/channels.hpp"

namespace hystloop::replay {

struct ReplayInputOptions {
  std::string compensator_process = "compensator";  // service_status_t.process of the recorded compensator
  bool only_answered = false;  // also drop sensor blocks the original did not answer (a gap it saw)
};

struct ReplayInputSelection {
  std::optional<std::int64_t> first_log_sample;       // first tick of the log's first sensor block
  std::optional<std::int64_t> first_answered_sample;  // lowest sample_seq (>= 0) among the logged command blocks
  std::optional<std::int64_t> compensator_start_utime;
  bool log_starts_after_compensator = false;    // inputs before the log began are unknown
  std::uint64_t blocks_written = 0;             // sensor blocks
  std::uint64_t ticks_written = 0;              // their ticks
  std::uint64_t blocks_before_start = 0;        // sensor blocks before the first answered one (warm-up), left out
  std::uint64_t blocks_unanswered = 0;          // later sensor blocks no command block of the original answered
  std::uint64_t blocks_unanswered_dropped = 0;  // of those, left out (only_answered)
  std::uint64_t other_inputs_written = 0;       // trajectory, scan, params, model, control
  std::uint64_t other_inputs_skipped = 0;       // logged before the compensator ran
  std::uint64_t undecodable = 0;                // input events that failed to decode or check (left out)
};

// Writes the inputs of `log` to `out` (an LCM event log, original timestamps kept).
// Throws std::runtime_error naming the file when one cannot be read or written, or when
// the log holds no command (nothing to replay against).
ReplayInputSelection write_replay_inputs(const std::filesystem::path& log, const std::filesystem::path& out,
                                         const ChannelNames& channels, const ReplayInputOptions& options);

// Human-readable summary of the selection, one fact per line.
std::string describe(const ReplayInputSelection& selection);

}  // namespace hystloop::replay
