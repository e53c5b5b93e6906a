#pragma once
// The compact human-readable summary hystloop-report prints: one line per figure.

#include <string>

#include "report_metrics.hpp"

namespace hystloop::report {

std::string format_table(const ReportMetrics& metrics);

}  // namespace hystloop::report
