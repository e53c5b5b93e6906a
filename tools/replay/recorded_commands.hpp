#pragma once
// The commands a compensator published, as an LCM event log holds them: its command_block_t
// blocks taken apart into one record per tick (blocks.hpp), the fields a replay compares.

#include <cstdint>
#include <filesystem>
#include <map>
#include <set>

#include "lcm/channels.hpp"

namespace hystloop::replay {

struct RecordedCommand {
  std::int64_t seq = 0;         // tick the command is for
  std::int64_t sample_seq = 0;  // last sensor tick the compensator had when it planned the block holding it
  double u_ff_V = 0.0;
  double y_ref_m = 0.0;  // NaN = no reference
  std::int32_t params_version = 0;
  std::int8_t mode = 0;
};

struct CommandLog {
  std::map<std::int64_t, RecordedCommand> by_seq;  // the first command logged for each tick
  std::set<std::int64_t> answered_samples;         // sample_seq (>= 0) of every decodable block
  std::uint64_t blocks = 0;                        // decodable blocks
  std::uint64_t duplicates = 0;                    // further commands for a tick already held (ignored)
  std::uint64_t undecodable = 0;                   // events on the command channel that failed to decode or check
  int axes = 0;                                    // the most axes a decodable block carried (a one-axis rig's: 1)
};

// Every command of `axis` (0: x) on channels.command; blocks without that axis hold none of it. Throws
// std::runtime_error naming the file if it cannot be opened as an LCM event log.
CommandLog read_commands(const std::filesystem::path& log, const ChannelNames& channels, int axis = 0);

// Ticks of the decodable sensor blocks on channels.sensor (every tick of every block).
std::set<std::int64_t> read_sample_seqs(const std::filesystem::path& log, const ChannelNames& channels);

}  // namespace hystloop::replay
