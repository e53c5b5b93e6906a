#pragma once
// Reads LCM event logs (event_file.hpp) into RunData. Several files are read in the order
// given, as one log (a rotated recording). Which channel is which comes from the rig
// prefix; a message on a known channel that does not decode or fails the contract's value
// check is counted in RunData::undecodable and skipped (a whole block, for HX_SENSOR and
// HX_COMMAND).

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "lcm/channels.hpp"
#include "lcm/rig_auth.hpp"
#include "run_data.hpp"

namespace hystloop::report {

// Throws std::runtime_error naming the file if one cannot be opened. What each file held
// beyond its events (junk, a truncated tail) is in RunData::files. `axis` (0 x, 1 y, 2 z) is the
// axis whose ticks, commands, true positions and parameter sets are kept (RunData::axis); a sensor
// block without it is left out whole and counted (RunData::blocks_without_axis).
RunData read_logs(const std::vector<std::filesystem::path>& files, const ChannelNames& channels, int axis = 0,
                  std::shared_ptr<const RigAuth> auth = process_rig_auth());

// "1 axis (x)", "2 axes (x and y)", "3 axes (x, y and z)".
std::string axes_text(int axes);

// Throws ParameterError("--axis", "the log's HX_SENSOR blocks carry 1 axis (x), not y") when the
// log has sensor blocks and none carries run.axis (a log without any is left to the report's
// warning).
void require_axis(const RunData& run, const std::string& sensor_channel);

// The time of tick i of a sensor block of n_ticks received at block_recv_utime (run_data.hpp):
// block_recv_utime - (n_ticks - 1 - i) * dt_s [us].
std::int64_t tick_recv_utime(std::int64_t block_recv_utime, std::int32_t n_ticks, std::size_t i, double dt_s) noexcept;

// Time zero of every t_s, as hystloop-report takes it (RunData::time_zero_utime), without reading
// the whole log: the first tick of the first sensor block that decodes, else the first event.
// Reading stops there, usually in the first block. [us]
std::int64_t log_time_zero_utime(const std::vector<std::filesystem::path>& files, const std::string& sensor_channel,
                                 std::shared_ptr<const RigAuth> auth = process_rig_auth());

// Calls visit(event) for every event of every file, in order (for exports that need
// whole messages), and says what each file held besides (LogFileScan). Throws
// std::runtime_error naming the file if one cannot be opened. With the rig's key (`auth`; by
// default the process's, which a tool's --key-file sets) an event on a signed channel whose
// signature fails is not visited, and counted (LogFileScan::unverified_left_out); without,
// a log its keyed logger marked is read unverified and said so (record/record_auth.hpp).
std::vector<LogFileScan> for_each_event(const std::vector<std::filesystem::path>& files,
                                        const std::function<void(const lcm::LogEvent&)>& visit,
                                        std::shared_ptr<const RigAuth> auth = process_rig_auth());

// The channels of a log's event counts, comma-separated ("HX_COMMAND, HX_SENSOR"), or "none".
std::string channel_list(const std::map<std::string, std::uint64_t>& counts);

// A channel named by `option` as logged ("HX_SENSOR") or by its suffix after the rig's prefix
// ("SENSOR"). Throws ParameterError(option, "no channel 'X' in the log (channels: ...)") when the
// log has neither.
std::string resolve_channel(const std::string& name, const std::map<std::string, std::uint64_t>& counts,
                            const std::string& prefix, const char* option);

// One warning per file that was not read cleanly, and its signature notes ("run.lcmlog: the last 17 bytes are not a
// complete event (truncated?)"); empty when every byte of every file was an event.
std::vector<std::string> describe_scan_problems(const std::vector<LogFileScan>& scans);

}  // namespace hystloop::report
