#include "runtime/status_reporter.hpp"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <limits>

#include "core/process.hpp"
#include "lcm/status_counters.hpp"

namespace hystloop {

StatusReporter::StatusReporter(lcm::LCM& lcm, const std::string& channel, std::string process)
    : publisher_(lcm, channel) {
  status_.process = std::move(process);
  status_.host = host_name();
  status_.pid = static_cast<std::int32_t>(::getpid());
  status_.start_utime = wall_utime();
  begin(service_status_t::STARTING);
}

void StatusReporter::begin(std::int8_t state, std::string detail) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  status_.state = state;
  status_.detail = std::move(detail);
  clear_counters(status_);
  status_.loop_p50_us = status_.loop_p99_us = status_.loop_max_us = kNaN;
  status_.latency_p50_us = status_.latency_p99_us = status_.latency_max_us = kNaN;
  status_.late = 0;
  status_.rejected = 0;
}

void StatusReporter::counter(std::string_view name, std::uint64_t value) { add_counter(status_, name, value); }

void StatusReporter::endpoint(std::string_view name, const EndpointCounters& counters) {
  add_endpoint_counters(status_, name, counters);
}

void StatusReporter::publisher(std::string_view name, const PublisherCounters& counters) {
  add_publisher_counters(status_, name, counters);
}

namespace {
void fill(const LatencyStats& stats, double& p50, double& p99, double& max) {
  if (stats.count() == 0) return;
  p50 = stats.percentile(0.50) / 1e3;
  p99 = stats.percentile(0.99) / 1e3;
  max = static_cast<double>(stats.max_ns()) / 1e3;
}
}  // namespace

void StatusReporter::loop_timing(const LatencyStats& stats) {
  fill(stats, status_.loop_p50_us, status_.loop_p99_us, status_.loop_max_us);
}

void StatusReporter::latency(const LatencyStats& stats) {
  fill(stats, status_.latency_p50_us, status_.latency_p99_us, status_.latency_max_us);
}

bool StatusReporter::publish(std::int64_t utime) {
  // Every process reports what it costs (hystloop-report turns these into cpu_fraction).
  const ResourceUsage usage = read_resource_usage();
  counter("cpu_user_us", static_cast<std::uint64_t>(usage.user_cpu_s * 1e6));
  counter("cpu_system_us", static_cast<std::uint64_t>(usage.system_cpu_s * 1e6));
  counter("peak_rss_kB", static_cast<std::uint64_t>(usage.peak_rss_bytes / 1024));
  status_.utime = utime;
  return publisher_.publish(status_);
}

}  // namespace hystloop
