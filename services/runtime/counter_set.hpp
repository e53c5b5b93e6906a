#pragma once
// A service's named counters, reported on HX_STATUS since the last RESET_COUNTERS. Counters
// only count up (and some belong to another thread), so a reset keeps a baseline taken at the
// reset and reports the difference. One type for every service; off the per-sample path.
// LCM endpoints' counters (received, accepted, rejected by reason; published, failed) are kept
// the same way, by endpoint name.

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "lcm/reject_reason.hpp"
#include "runtime/status_reporter.hpp"

namespace hystloop {

class CounterSet {
 public:
  // Cumulative values, by name, in the order they are reported.
  using Entries = std::vector<std::pair<std::string, std::uint64_t>>;

  // Reports every entry as its value since the baseline (status.counter).
  void report(StatusReporter& status, const Entries& now) const;
  // The value of one entry since the baseline.
  std::uint64_t since(const std::string& name, std::uint64_t value) const;
  // RESET_COUNTERS: the baseline becomes `now`.
  void rebase(const Entries& now);

  // The same for an LCM subscription or publisher, reported as "<name>.<counter>".
  void report(StatusReporter& status, const std::string& name, const EndpointCounters& now) const;
  void report(StatusReporter& status, const std::string& name, const PublisherCounters& now) const;
  void rebase(const std::string& name, const EndpointCounters& now) { endpoint_baseline_[name] = now; }
  void rebase(const std::string& name, const PublisherCounters& now) { publisher_baseline_[name] = now; }

 private:
  std::map<std::string, std::uint64_t, std::less<>> baseline_;
  std::map<std::string, EndpointCounters, std::less<>> endpoint_baseline_;
  std::map<std::string, PublisherCounters, std::less<>> publisher_baseline_;
};

}  // namespace hystloop
