#pragma once
// Reads LCM event logs (lcm::LogFile) into RunData. Several files are read in the order
// given, as one log (a rotated recording). Which channel is which comes from the rig
// prefix; a message on a known channel that does not decode or fails the contract's value
// check is counted in RunData::undecodable and skipped.

#include <filesystem>
#include <functional>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "lcm/channels.hpp"
#include "run_data.hpp"

namespace hystloop::report {

// Throws std::runtime_error naming the file if one cannot be opened.
RunData read_logs(const std::vector<std::filesystem::path>& files, const ChannelNames& channels);

// Calls visit(event) for every event of every file, in order (for exports that need
// whole messages). Throws std::runtime_error naming the file if one cannot be opened.
void for_each_event(const std::vector<std::filesystem::path>& files,
                    const std::function<void(const lcm::LogEvent&)>& visit);

}  // namespace hystloop::report
