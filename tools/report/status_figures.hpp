#pragma once
// The figures of a run that come from the processes' HX_STATUS reports (and the fallbacks
// computed from the ticks when a report lacks them). Part of compute_metrics.

#include <cstdint>

#include "report_metrics.hpp"
#include "run_data.hpp"

namespace hystloop::report {

// commands_rejected: the bridge's command reject counters (leaf "rejected*" or "stale" of no
// other endpoint), else its 'rejected' field.
void fill_commands_rejected(const RunData& run, const ReportOptions& options, std::int64_t upper_utime,
                            ReportMetrics& m);

// logger_gaps: the logger's gap counter ("gaps", then "*gaps", then "*gap*"), else m.seq_gaps.
void fill_logger_gaps(const RunData& run, const ReportOptions& options, std::int64_t upper_utime, ReportMetrics& m);

// watchdog_trips: the bridge's counter "watchdog_trips", else `transitions` (armed -> SAFE_STATE
// changes between consecutive ticks that no DISARM/SHUTDOWN request explains).
void fill_watchdog_trips(const RunData& run, const ReportOptions& options, std::int64_t upper_utime,
                         std::int64_t transitions, ReportMetrics& m);

// cpu_fraction per process: (cpu_user_us + cpu_system_us) between its first and last status
// received in [lower_utime, upper_utime], over the wall time between them (the statuses' utime).
// A restart (start_utime changes) or a counter reset starts a new segment; the segments add up.
// Null for a process without two such statuses.
void fill_cpu_fraction(const RunData& run, std::int64_t lower_utime, std::int64_t upper_utime, ReportMetrics& m);

}  // namespace hystloop::report
