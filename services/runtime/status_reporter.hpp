#pragma once
// Builds and publishes a process's service_status_t once per report period (1 Hz by
// default). Off the per-sample path: it builds strings. A service fills the counters
// and timings it has, then calls publish().

#include <cstdint>
#include <string>
#include <string_view>

#include <lcm/lcm-cpp.hpp>

#include "core/clock.hpp"  // wall_utime() for utime fields
#include "core/latency_stats.hpp"
#include "hystloop/service_status_t.hpp"
#include "lcm/publisher.hpp"
#include "lcm/reject_reason.hpp"

namespace hystloop {

class StatusReporter {
 public:
  StatusReporter(lcm::LCM& lcm, const std::string& channel, std::string process);

  // Starts a new report: clears counters and timings, keeps process/host/pid/start.
  void begin(std::int8_t state, std::string detail = {});
  void counter(std::string_view name, std::uint64_t value);
  void endpoint(std::string_view name, const EndpointCounters& counters);  // adds to rejected
  void publisher(std::string_view name, const PublisherCounters& counters);
  void loop_timing(const LatencyStats& stats);  // per-iteration work
  void latency(const LatencyStats& stats);      // sample-to-command
  void late(std::int64_t count) { status_.late = count; }
  void add_rejected(std::int64_t count) { status_.rejected += count; }
  // Adds the process's CPU time and peak memory (cpu_user_us, cpu_system_us, peak_rss_kB), then publishes.
  bool publish(std::int64_t utime);

  const service_status_t& status() const noexcept { return status_; }

  // A report that is not the periodic one (the verdict a sender waits for, a disk fault) goes
  // out at once only if none went out within this interval; otherwise it is due and goes out
  // when the interval has passed, however many asked meanwhile (one report says it all). With
  // the periodic report a process then sends at most 1 s / interval + 1 reports a second,
  // whatever floods it.
  static constexpr std::int64_t kMinImmediateInterval_ns = 100'000'000;
  // True if an immediate report may be published at now_ns (monotonic_ns()).
  bool immediate_allowed(std::int64_t now_ns) const noexcept {
    return published_ == 0 || now_ns - last_publish_ns_ >= kMinImmediateInterval_ns;
  }
  // Reports published so far.
  std::uint64_t published() const noexcept { return published_; }

  // Counters beyond service_status_t::MAX_COUNTERS are not silently lost: the report's last
  // counter becomes `counters_dropped` (how many did not fit, that one included), and the first
  // report that overflows logs their names.
  static constexpr std::string_view kDroppedCounter = "counters_dropped";

 private:
  void count_drop(bool added, std::string_view name);
  void count_group_drop(std::uint64_t dropped, std::string_view name);  // a group named name.*

  service_status_t status_{};
  std::uint64_t dropped_ = 0;  // counters of this report that did not fit
  std::string first_dropped_;  // ... the first of them, for the log
  bool overflow_logged_ = false;
  std::int64_t last_publish_ns_ = 0;
  std::uint64_t published_ = 0;
  Publisher<service_status_t> publisher_;
};

}  // namespace hystloop
