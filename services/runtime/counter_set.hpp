#pragma once
// A service's named counters, reported on HX_STATUS since the last RESET_COUNTERS. Counters
// only count up (and some belong to another thread), so a reset keeps a baseline taken at the
// reset and reports the difference. One type for every service; off the per-sample path.
// (An LCM endpoint's counters go through counters_since in runtime/counter_baseline.hpp.)

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

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

 private:
  std::map<std::string, std::uint64_t, std::less<>> baseline_;
};

}  // namespace hystloop
