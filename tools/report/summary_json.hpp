#pragma once
// summary.json: every figure of ReportMetrics, in SI units (metres, seconds; ticks and
// fractions as the names say), null where a figure could not be computed.

#include <filesystem>
#include <string>
#include <vector>

#include "report_metrics.hpp"

namespace hystloop::report {

std::string summary_json(const ReportMetrics& metrics, const ReportOptions& options,
                         const std::vector<std::filesystem::path>& files);

}  // namespace hystloop::report
