#pragma once
// A deliberately altered copy of a log, for the tests that prove a replay notices a change:
// the feedforward of one tick (u_ff_V, inside the command block that first carried it) gets
// a different value, every other event and tick is copied unchanged.

#include <cstdint>
#include <filesystem>
#include <optional>

#include "lcm/channels.hpp"

namespace hystloop::replay {

struct CommandAlteration {
  std::int64_t seq = 0;             // tick of the command to alter (unless nth is set)
  std::optional<std::int64_t> nth;  // else: the nth tick commanded in the log (1 = first; a tick repeated
                                    // by a later block counts once), whatever its number
  std::optional<double> delta_V;    // add this to u_ff_V; unset: flip its least significant mantissa bit (1 ulp)
};

struct AlterationResult {
  std::int64_t seq = 0;  // tick of the altered command
  double old_u_ff_V = 0.0;
  double new_u_ff_V = 0.0;
};

// Throws std::runtime_error naming the file if a log cannot be read or written, or if the
// log holds no decodable command for `alteration.seq` (or fewer than `nth` ticks).
AlterationResult write_altered_log(const std::filesystem::path& log, const std::filesystem::path& out,
                                   const ChannelNames& channels, const CommandAlteration& alteration);

}  // namespace hystloop::replay
