#pragma once
// hystloop-report's scan step (scan_figures.hpp, scan_output.hpp): after the usual report, the
// scan table when asked for (--scan) or when the log holds two or more periodic trajectories
// (deploy/hystloop scan), unless --no-scan. The whole log, whatever --from/--to.

#include <filesystem>
#include <string>
#include <vector>

#include "lcm/channels.hpp"
#include "plots.hpp"
#include "run_data.hpp"
#include "scan_figures.hpp"

namespace hystloop::report {

struct ScanReportOptions {
  bool force = false;  // --scan: even for a single periodic trajectory
  bool off = false;    // --no-scan
  ScanOptions figures;
  std::string compensator_process = "compensator";
  int axis = 0;           // whose trajectories (--axis); RunData's ticks must be of it
  bool quiet = false;     // print no table
  bool no_plots = false;  // write no PNG
  PlotOptions plots;
};

// Writes DIR/scan.json, scan.md and the plots, prints the table (unless quiet) and warns on
// stderr about the segments the bridge clamped in. Returns 0, or 1 when --scan found no periodic
// trajectory. Throws std::runtime_error when a file cannot be read or written.
int write_scan_report(const std::vector<std::filesystem::path>& logs, const RunData& data, const ChannelNames& channels,
                      const std::filesystem::path& dir, const ScanReportOptions& options);

}  // namespace hystloop::report
