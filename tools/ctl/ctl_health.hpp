#pragma once
// `hystloop-ctl status`: the latest HX_STATUS report of each process, one line each, and
// the --wait-healthy verdict. No I/O here: the caller feeds the reports in.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "hystloop/service_status_t.hpp"
#include "lcm/status_counters.hpp"  // find_counter

namespace hystloop::ctl {

// "STARTING", "HEALTHY", "DEGRADED", "SAFE", "STOPPING", or "state <n>".
std::string state_name(std::int8_t state);

// The latest report of each process heard.
class StatusBoard {
 public:
  void update(const service_status_t& status) { processes_[status.process] = status; }
  const std::map<std::string, service_status_t>& processes() const noexcept { return processes_; }

 private:
  std::map<std::string, service_status_t> processes_;
};

struct HealthVerdict {
  bool healthy = false;
  std::vector<std::string> problems;  // "bridge: no status", "compensator: DEGRADED (late commands)"
};

// Every process in `required` has reported HEALTHY in its latest report, or SAFE if it
// is listed in `accept_safe`, or DEGRADED when accept_degraded (it is serving, with a
// complaint: e.g. a logger that saw a gap while the rig started).
HealthVerdict check_health(const StatusBoard& board, const std::vector<std::string>& required,
                           const std::vector<std::string>& accept_safe, bool accept_degraded = false);

// One line: process, state, pid@host, uptime, late/rejected, loop and latency timing, detail.
// With all_counters, the named counters follow, one per indented line.
std::string format_status(const service_status_t& status, bool all_counters);

}  // namespace hystloop::ctl
