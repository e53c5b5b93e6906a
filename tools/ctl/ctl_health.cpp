#include "ctl_health.hpp"

#include <algorithm>
#include <cmath>

#include <spdlog/fmt/fmt.h>

namespace hystloop::ctl {

namespace {

std::string timing(double p50, double p99, double max) {
  if (!std::isfinite(p50) && !std::isfinite(p99) && !std::isfinite(max)) return "--";
  auto one = [](double v) {
    if (!std::isfinite(v)) return std::string("--");
    return v < 100.0 ? fmt::format("{:.1f}", v) : fmt::format("{:.0f}", v);
  };
  return one(p50) + "/" + one(p99) + "/" + one(max) + " us";
}

}  // namespace

std::string state_name(std::int8_t state) {
  switch (state) {
    case service_status_t::STARTING: return "STARTING";
    case service_status_t::HEALTHY: return "HEALTHY";
    case service_status_t::DEGRADED: return "DEGRADED";
    case service_status_t::SAFE: return "SAFE";
    case service_status_t::STOPPING: return "STOPPING";
    default: return "state " + std::to_string(state);
  }
}

HealthVerdict check_health(const StatusBoard& board, const std::vector<std::string>& required,
                           const std::vector<std::string>& accept_safe, bool accept_degraded) {
  HealthVerdict verdict;
  for (const auto& name : required) {
    const auto it = board.processes().find(name);
    if (it == board.processes().end()) {
      verdict.problems.push_back(name + ": no status received");
      continue;
    }
    const service_status_t& s = it->second;
    const bool safe_ok = std::find(accept_safe.begin(), accept_safe.end(), name) != accept_safe.end();
    if (s.state == service_status_t::HEALTHY || (safe_ok && s.state == service_status_t::SAFE) ||
        (accept_degraded && s.state == service_status_t::DEGRADED)) {
      continue;
    }
    verdict.problems.push_back(name + ": " + state_name(s.state) + (s.detail.empty() ? "" : " (" + s.detail + ")"));
  }
  verdict.healthy = verdict.problems.empty();
  return verdict;
}

std::string format_status(const service_status_t& s, bool all_counters) {
  const double up_s = static_cast<double>(s.utime - s.start_utime) * 1e-6;
  std::string line = fmt::format("{:<12} {:<9} pid {}@{}  up {:.0f} s  late {}  rejected {}", s.process,
                                 state_name(s.state), s.pid, s.host, up_s, s.late, s.rejected);
  line += "  loop p50/p99/max " + timing(s.loop_p50_us, s.loop_p99_us, s.loop_max_us);
  line += "  latency " + timing(s.latency_p50_us, s.latency_p99_us, s.latency_max_us);
  if (!s.detail.empty()) line += "  [" + s.detail + "]";
  if (all_counters) {
    for (std::size_t i = 0; i < s.counter_names.size() && i < s.counter_values.size(); ++i) {
      line += "\n    " + s.counter_names[i] + " = " + std::to_string(s.counter_values[i]);
    }
  }
  return line;
}

}  // namespace hystloop::ctl
