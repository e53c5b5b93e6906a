#pragma once
// hystloop-report's scan-path step (path_figures.hpp, path_output.hpp): for a log that holds paths
// on HX_SCAN, each path the compensator took measured per axis, the table printed, raster.csv and
// the error maps written. The whole log, whatever --from/--to: a path is measured over its own
// loop time.

#include <filesystem>
#include <string>
#include <vector>

#include "error_map.hpp"
#include "lcm/channels.hpp"
#include "path_figures.hpp"
#include "plots.hpp"
#include "run_data.hpp"

namespace hystloop::report {

struct PathReportOptions {
  std::string compensator_process = "compensator";
  ErrorMapOptions map;
  bool quiet = false;     // print no table
  bool no_plots = false;  // write no error map
  PlotOptions plots;
};

// The log's paths, each measured or with why not; empty when the log has no HX_SCAN event (the
// logs are not read again then). Throws std::runtime_error when a file cannot be read.
std::vector<PathFigures> compute_path_report(const std::vector<std::filesystem::path>& logs, const RunData& data,
                                             const ChannelNames& channels, const PathReportOptions& options);

// Writes DIR/raster.csv and the error maps, prints the table (unless quiet) and the warnings on
// stderr; nothing when `paths` is empty. Throws std::runtime_error when a file cannot be written.
void write_path_report(const std::vector<PathFigures>& paths, const ChannelNames& channels,
                       const std::filesystem::path& dir, const PathReportOptions& options);

}  // namespace hystloop::report
