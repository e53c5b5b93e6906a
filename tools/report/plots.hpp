#pragma once
// The report's plots: data files and a gnuplot script written into the output folder
// (so a user can edit and re-run `gnuplot plots.gp` there), then rendered to PNG with
// gnuplot's pngcairo terminal, or its libgd png terminal where cairo is missing.
//   hysteresis_u_y.png     applied voltage u -> measured y (the stage's hysteresis loop), coloured
//                          by phase (identification experiment, tracking, the rest: u_y_*.dat),
//                          the MEM model's y for the same u dashed on top (model_overlay.hpp)
//   hysteresis_yref_y.png  reference y_ref -> measured y with and without compensation, as the MEM
//                          paper's Fig. 11 (yref_y_*.dat; the title says when the log has only one)
//   tracking_error.png     e = y_ref - y over time [nm], with the per-second RMS
//   convergence.png        c1 (with the held-out RMS), c2 and c3 of the published sets over time
//                          above the per-second RMS, every swap marked at its tick
//                          (convergence_plot.hpp; params.dat: one row per set)
//   run_ahead_histogram.png  run-ahead margin of the command blocks [ticks]
// The per-tick files (track.dat, u_y_*.dat, yref_y_*.dat) hold at most about max_points rows:
// gnuplot's time grows with the points, and a 30 s run at 10 kHz has 300k ticks.
// A plot whose data is empty is left out of the script.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "report_metrics.hpp"

namespace hystloop::report {

struct PlotOptions {
  std::string gnuplot = "gnuplot";                   // executable, searched in PATH unless it contains '/'
  std::size_t max_points = 20'000;                   // the per-tick data files are decimated to at most this many rows
  std::function<void(const std::string&)> progress;  // told as a long step starts (may be empty)
};

struct PlotResult {
  std::vector<std::filesystem::path> data_files;  // always written
  std::filesystem::path script;                   // always written
  std::vector<std::filesystem::path> images;      // rendered PNGs (empty without gnuplot)
  std::string terminal;                           // "pngcairo", "png" or empty
  std::string warning;                            // why images are missing, empty when all went well
};

// A gnuplot script of the report and what it draws.
struct GnuplotScript {
  std::string name;                 // "plots.gp", written into the output folder
  std::string text;                 // "@TERMINAL@" stands for the PNG terminal
  std::vector<std::string> images;  // the PNGs it draws
  std::string log;                  // gnuplot's output, in the output folder: "gnuplot.log"
  std::string what;                 // the plots, in the warnings: "plots", "scan plots"
  std::string nothing;              // the warning when there is no image: "no data to plot"
};

// Writes the script into `dir` for pngcairo, then renders its images with gnuplot there, with
// pngcairo or, where cairo is missing, libgd's png (the script rewritten for it). Sets result's
// script, images, terminal and warning. Throws std::runtime_error if the script cannot be written.
void render_script(const GnuplotScript& script, const std::filesystem::path& dir, const PlotOptions& options,
                   PlotResult& result);

// Writes the data and the script into `dir` and runs gnuplot there.
// Throws std::runtime_error if a file cannot be written.
PlotResult write_plots(const std::vector<TrackPoint>& ticks, const ReportMetrics& metrics,
                       const std::filesystem::path& dir, const PlotOptions& options);

}  // namespace hystloop::report
