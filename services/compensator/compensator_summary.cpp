// CompensatorService::write_summary_json: the run's figures at exit (--summary-json), the same as
// the "summary:" log lines, for scripts (bench/run-all) that should not read log lines.
#include <cstdio>

#include <spdlog/spdlog.h>

#include "compensator/compensator_service.hpp"

namespace hystloop {

void CompensatorService::write_summary_json() const {
  if (summary_json_path_.empty()) return;
  const CompensatorCounters& c = compensator_->counters();
  const bool timed = latency_total_.count() > 0;
  const std::string json = fmt::format(
      "{{\"samples\": {}, \"command_ticks\": {}, \"command_blocks\": {}, \"ticks_planned_too_late\": {}, "
      "\"gaps\": {}, \"out_of_order\": {}, \"params_accepted\": {}, \"params_refused\": {}, \"params_swapped\": {}, "
      "\"params_invalid\": {}, \"block_to_answer_us\": {{\"p50\": {:.1f}, \"p99\": {:.1f}, \"max\": {:.1f}, "
      "\"count\": {}}}}}\n",
      c.samples, counters_.command_ticks_published, counters_.command_blocks_published, c.ticks_behind, c.gaps,
      c.out_of_order, c.params_accepted, c.params_rejected + counters_.params_refused, c.params_swapped,
      counters_.params_invalid, timed ? latency_total_.percentile(0.5) / 1e3 : -1.0,
      timed ? latency_total_.percentile(0.99) / 1e3 : -1.0,
      timed ? static_cast<double>(latency_total_.max_ns()) / 1e3 : -1.0, latency_total_.count());
  std::FILE* f = std::fopen(summary_json_path_.c_str(), "w");
  if (f == nullptr || std::fputs(json.c_str(), f) < 0 || std::fclose(f) != 0) {
    spdlog::error("could not write the summary to {}", summary_json_path_);
  }
}

}  // namespace hystloop
