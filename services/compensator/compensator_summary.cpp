// CompensatorService::write_summary_json: the run's figures at exit (--summary-json), the same as
// the "summary:" log lines, for scripts (bench/run-all) that should not read log lines.
#include <cmath>
#include <exception>

#include <spdlog/spdlog.h>

#include "compensator/compensator_service.hpp"
#include "runtime/summary_file.hpp"

namespace hystloop {

void CompensatorService::write_summary_json() const {
  if (summary_json_path_.empty()) return;
  const CompensatorCounters& c = compensator_->counters();
  const bool timed = latency_total_.count() > 0;
  // One decimal for the latencies [us], as the log lines print them.
  const auto us = [](double v) { return v < 0 ? v : std::round(v * 10.0) / 10.0; };
  const nlohmann::ordered_json json = {
      {"samples", c.samples},
      {"command_ticks", counters_.command_ticks_published},
      {"command_blocks", counters_.command_blocks_published},
      {"ticks_planned_too_late", c.ticks_behind},
      {"gaps", c.gaps},
      {"out_of_order", c.out_of_order},
      {"params_accepted", c.params_accepted},
      {"params_refused", c.params_rejected + counters_.params_refused},
      {"params_swapped", c.params_swapped},
      {"params_invalid", counters_.params_invalid},
      {"block_to_answer_us",
       {{"p50", us(timed ? latency_total_.percentile(0.5) / 1e3 : -1.0)},
        {"p99", us(timed ? latency_total_.percentile(0.99) / 1e3 : -1.0)},
        {"max", us(timed ? static_cast<double>(latency_total_.max_ns()) / 1e3 : -1.0)},
        {"count", latency_total_.count()}}},
  };
  try {
    write_file_atomically(summary_json_path_, to_json_text(json));
  } catch (const std::exception& e) {
    spdlog::error("could not write the summary: {}", e.what());
  }
}

}  // namespace hystloop
