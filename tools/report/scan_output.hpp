#pragma once
// What hystloop-report writes for a scan (scan_figures.hpp), into the output folder:
//   scan.json             every figure of every reference and learning state (SI: metres,
//                         seconds), with the per-period RMS series; null where none
//   scan.md               the table (scan_table()) and the per-period RMS with learning on
//   scan_error.png        e = y_ref - y against the time since the reference started (learning off,
//                         then on), one panel per reference (scan_error.dat, min/max per bucket)
//   scan_rms_vs_rate.png  RMS over each segment's last second against the line rate, per shape,
//                         learning off and on (scan_rates.dat)
//   scan_periods.png      the RMS of each period with learning on, per reference (scan_periods.dat)
// with the gnuplot script scan.gp beside them (re-run with `gnuplot scan.gp` there).

#include <filesystem>
#include <string>
#include <vector>

#include "plots.hpp"
#include "run_data.hpp"
#include "scan_figures.hpp"

namespace hystloop::report {

std::string scan_json(const ScanResult& scan, const std::vector<std::filesystem::path>& files);

// A Markdown table: one row per reference and learning state ("refused: WHY" for a refused one).
std::string scan_table(const ScanResult& scan);

// The data files, scan.gp and the PNGs (via gnuplot, as plots.hpp does). Throws
// std::runtime_error if a file cannot be written; a missing gnuplot is PlotResult::warning.
PlotResult write_scan_plots(const RunData& run, const ScanResult& scan, const std::filesystem::path& dir,
                            const PlotOptions& options);

}  // namespace hystloop::report
