#include "runtime/status_reporter.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cmath>
#include <limits>

#include <spdlog/spdlog.h>

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
  dropped_ = 0;
  first_dropped_.clear();
}

void StatusReporter::count_drop(bool added, std::string_view name) {
  if (added) return;
  if (dropped_ == 0) first_dropped_ = name;
  ++dropped_;
}

void StatusReporter::counter(std::string_view name, std::uint64_t value) {
  count_drop(add_counter(status_, name, value), name);
}

namespace {
// Adds a group of counters with `add` (add_endpoint_counters, ...); returns how many of them did
// not fit: those a complete set has beyond what `status` took.
template <class Add>
std::uint64_t add_group(service_status_t& status, Add&& add) {
  const std::int32_t before = status.n_counters;
  if (add(status)) return 0;
  service_status_t whole{};
  add(whole);
  return static_cast<std::uint64_t>(whole.n_counters - (status.n_counters - before));
}
}  // namespace

void StatusReporter::count_group_drop(std::uint64_t dropped, std::string_view name) {
  if (dropped == 0) return;
  if (dropped_ == 0) first_dropped_ = std::string(name) + ".*";
  dropped_ += dropped;
}

void StatusReporter::endpoint(std::string_view name, const EndpointCounters& counters) {
  count_group_drop(add_group(status_, [&](service_status_t& s) { return add_endpoint_counters(s, name, counters); }),
                   name);
}

void StatusReporter::publisher(std::string_view name, const PublisherCounters& counters) {
  count_group_drop(add_group(status_, [&](service_status_t& s) { return add_publisher_counters(s, name, counters); }),
                   name);
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
  if (dropped_ > 0 && status_.n_counters > 0) {
    // The last slot says so: a reader finds the loss in the report itself.
    const std::size_t last = static_cast<std::size_t>(status_.n_counters) - 1;
    ++dropped_;
    status_.counter_names[last] = std::string(kDroppedCounter);
    status_.counter_values[last] = static_cast<std::int64_t>(std::min<std::uint64_t>(dropped_, INT64_MAX));
    if (!overflow_logged_) {
      overflow_logged_ = true;
      spdlog::error("HX_STATUS: {} counters beyond the {} a report holds were dropped, from '{}' on (reported as {})",
                    dropped_, service_status_t::MAX_COUNTERS, first_dropped_, kDroppedCounter);
    }
  }
  status_.utime = utime;
  last_publish_ns_ = monotonic_ns();
  ++published_;
  return publisher_.publish(status_);
}

}  // namespace hystloop
