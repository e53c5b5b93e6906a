// CompensatorService::write_summary_json: the run's figures at exit (--summary-json): the counters
// HX_STATUS carries, under the same names, for scripts (bench/run-all) that should not read log lines.

#include <spdlog/spdlog.h>

#include "compensator/compensator_service.hpp"
#include "runtime/summary_file.hpp"

namespace hystloop {

void CompensatorService::write_summary_json() const {
  if (summary_json_path_.empty()) return;
  // Every counter under its HX_STATUS name (the same list, collect_counters()), over the whole run
  // (the control laws a bridge restart retired included), then the latency.
  nlohmann::ordered_json json;
  for (const auto& [name, value] : collect_counters()) json[name] = value;
  json["block_to_answer_us"] = latency_summary_us(latency_total_);
  write_summary_file(summary_json_path_, json);
}

}  // namespace hystloop
