#pragma once
// The report's plots: data files and a gnuplot script written into the output folder
// (so a user can edit and re-run `gnuplot plots.gp` there), then rendered to PNG with
// gnuplot's pngcairo terminal, or its libgd png terminal where cairo is missing.
//   hysteresis_u_y.png     applied voltage u -> measured y (the stage's hysteresis loop)
//   hysteresis_yref_y.png  reference y_ref -> measured y (as the MEM paper's Fig. 11)
//   tracking_error.png     e = y_ref - y over time [nm], with the per-second RMS
//   convergence.png        the published parameter sets over time above the per-second RMS, every
//                          swap marked (params.dat: one row per set)
//   run_ahead_histogram.png  run-ahead margin of the command blocks [ticks]
// A plot whose data is empty is left out of the script.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "report_metrics.hpp"

namespace hystloop::report {

struct PlotOptions {
  std::string gnuplot = "gnuplot";   // executable, searched in PATH unless it contains '/'
  std::size_t max_points = 200'000;  // track.dat is decimated to at most this many rows
};

struct PlotResult {
  std::vector<std::filesystem::path> data_files;  // always written
  std::filesystem::path script;                   // always written
  std::vector<std::filesystem::path> images;      // rendered PNGs (empty without gnuplot)
  std::string terminal;                           // "pngcairo", "png" or empty
  std::string warning;                            // why images are missing, empty when all went well
};

// Writes the data and the script into `dir` and runs gnuplot there.
// Throws std::runtime_error if a file cannot be written.
PlotResult write_plots(const std::vector<TrackPoint>& ticks, const ReportMetrics& metrics,
                       const std::filesystem::path& dir, const PlotOptions& options);

// Full path of an executable (PATH search unless `name` contains '/'), empty if none.
std::filesystem::path find_executable(const std::string& name);

}  // namespace hystloop::report
