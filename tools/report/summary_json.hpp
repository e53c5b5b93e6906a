#pragma once
// summary.json: every figure of ReportMetrics, in SI units (metres, seconds; ticks and
// fractions as the names say), null where a figure could not be computed; "axis" names the axis
// they are of. A log with paths on HX_SCAN adds "scan_paths" (path_output.hpp's paths_json).

#include <filesystem>
#include <string>
#include <vector>

#include "path_figures.hpp"
#include "report_metrics.hpp"

namespace hystloop::report {

std::string summary_json(const ReportMetrics& metrics, const ReportOptions& options,
                         const std::vector<std::filesystem::path>& files, const std::vector<PathFigures>& paths = {});

}  // namespace hystloop::report
