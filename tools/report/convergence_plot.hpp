#pragma once
// convergence.png's gnuplot commands: the published parameter sets over time (a panel each for
// c1 with the held-out RMS of every set, c2 and c3: their scales differ by orders of magnitude)
// above the per-second tracking RMS, every panel titled on its own, and every swap — the first
// tick the compensator commanded with another version (ReportMetrics::swaps) — marked by a
// dashed line at that tick's time on all panels. Reads params.dat and per_second.dat (plots.hpp).

#include <string>

#include "report_metrics.hpp"

namespace hystloop::report {

// The script section (starts with "set output 'convergence.png'", leaves no title, arrow,
// label, range or multiplot behind); empty when there is no parameter set or no second.
std::string convergence_script(const ReportMetrics& metrics);

}  // namespace hystloop::report
