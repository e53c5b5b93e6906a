// CompensatorService::write_summary_json: the run's figures at exit (--summary-json), the same as
// the "summary:" log lines, for scripts (bench/run-all) that should not read log lines.

#include <spdlog/spdlog.h>

#include "compensator/compensator_service.hpp"
#include "runtime/summary_file.hpp"

namespace hystloop {

void CompensatorService::write_summary_json() const {
  if (summary_json_path_.empty()) return;
  const CompensatorCounters& c = compensator_->counters();
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
      {"block_to_answer_us", latency_summary_us(latency_total_)},
  };
  write_summary_file(summary_json_path_, json);
}

}  // namespace hystloop
