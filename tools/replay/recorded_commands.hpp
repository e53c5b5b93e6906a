#pragma once
// The commands a compensator published, as an LCM event log holds them: one record per
// tick (actuator_command_t.seq), the fields a replay compares.

#include <cstdint>
#include <filesystem>
#include <map>
#include <set>

#include "lcm/channels.hpp"

namespace hystloop::replay {

struct RecordedCommand {
  std::int64_t seq = 0;         // tick the command is for
  std::int64_t sample_seq = 0;  // tick of the sample it answers
  double u_V = 0.0;
  double u_ff_V = 0.0;
  double u_fb_V = 0.0;
  double y_ref_m = 0.0;
  std::int32_t params_version = 0;
  std::int8_t mode = 0;
};

struct CommandLog {
  std::map<std::int64_t, RecordedCommand> by_seq;  // the first command logged for each tick
  std::uint64_t duplicates = 0;                    // further commands for a tick already held (ignored)
  std::uint64_t undecodable = 0;                   // events on the command channel that failed to decode or check
};

// Every command on channels.command. Throws std::runtime_error naming the file if it
// cannot be opened as an LCM event log.
CommandLog read_commands(const std::filesystem::path& log, const ChannelNames& channels);

// Ticks (seq) of the decodable sensor samples on channels.sensor.
std::set<std::int64_t> read_sample_seqs(const std::filesystem::path& log, const ChannelNames& channels);

}  // namespace hystloop::replay
