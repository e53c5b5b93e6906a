#pragma once
// What the scan-path table (path_figures.hpp) needs from a log: the paths sent on HX_SCAN (a
// raster or a Lissajous figure of every axis, scan_t), the compensator's HX_STATUS reports (its
// verdict on each path, under the path's version), and the ticks of every axis in the loop time
// the paths ran. Times are the log's receive timestamps, the clock of RunData.
//
// Two passes over the log, so that a long recording is never held whole: read_path_events first,
// then read_path_ticks for the loop-time windows the verdicts name.

#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <variant>
#include <vector>

#include "hystloop/scan_t.hpp"
#include "lcm/channels.hpp"
#include "loop/scan_path.hpp"
#include "scan_log.hpp"

namespace hystloop::report {

// One path as sent. Its start_s is 0 and a raster's corner_s is as sent (0: the compensator's
// choice): the compensator's verdict and the logged reference give both (path_figures.hpp).
struct LoggedPath {
  std::int64_t recv_utime = 0;  // its first receipt (a sender repeats it over UDP)
  std::int64_t version = 0;
  std::variant<RasterSpec, LissajousSpec> path;
  double blend_s = 0.0;
  bool decouple = true;
  std::int64_t start_utime = 0;  // 0: as soon as the approach allows
};

// scan_t -> LoggedPath (no validation: a message that passed the contract's check).
LoggedPath logged_path(const scan_t& msg, std::int64_t recv_utime);

struct PathEvents {
  std::vector<LoggedPath> paths;                   // in log order, one per version
  std::vector<ScanCompensatorStatus> compensator;  // its reports, in log order
};

// Reads `files` in order. Events that do not decode are skipped (the report's reader counts
// them). Throws std::runtime_error naming a file that cannot be opened.
PathEvents read_path_events(const std::vector<std::filesystem::path>& files, const ChannelNames& channels,
                            const std::string& compensator_process);

inline constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

// One tick of every axis (entries at and beyond `axes`: NaN).
struct PathTick {
  std::int64_t seq = 0;
  std::int64_t recv_utime = 0;  // dated as RunData dates a sensor tick
  double dt_s = 0.0;            // its block's tick period: loop time = seq * dt_s
  int axes = 1;
  bool safe = false;  // SAFE_STATE
  AxisPositions y_ref_m{kNoValue, kNoValue, kNoValue};
  AxisPositions y_m{kNoValue, kNoValue, kNoValue};
  AxisPositions y_true_m{kNoValue, kNoValue, kNoValue};  // HX_SIM_TRUTH's; NaN: none
  double t_s() const noexcept { return static_cast<double>(seq) * dt_s; }
};

// A span of loop time [from_s, to_s].
struct LoopWindow {
  double from_s = 0.0;
  double to_s = 0.0;
};

// The ticks of every sensor block with a tick whose loop time falls in a window, in log order,
// with their true positions (matched by seq and n_ticks, as read_logs does). Throws
// std::runtime_error naming a file that cannot be opened.
std::vector<PathTick> read_path_ticks(const std::vector<std::filesystem::path>& files, const ChannelNames& channels,
                                      const std::vector<LoopWindow>& windows);

}  // namespace hystloop::report
