#include "runtime/counter_set.hpp"

#include "runtime/counter_baseline.hpp"

namespace hystloop {

void CounterSet::report(StatusReporter& status, const Entries& now) const {
  for (const auto& [name, value] : now) status.counter(name, since(name, value));
}

std::uint64_t CounterSet::since(const std::string& name, std::uint64_t value) const {
  const auto it = baseline_.find(name);
  if (it == baseline_.end() || it->second > value) return value;
  return value - it->second;
}

void CounterSet::rebase(const Entries& now) {
  for (const auto& [name, value] : now) baseline_[name] = value;
}

void CounterSet::report(StatusReporter& status, const std::string& name, const EndpointCounters& now) const {
  const auto it = endpoint_baseline_.find(name);
  status.endpoint(name, it == endpoint_baseline_.end() ? now : counters_since(now, it->second));
}

void CounterSet::report(StatusReporter& status, const std::string& name, const PublisherCounters& now) const {
  const auto it = publisher_baseline_.find(name);
  status.publisher(name, it == publisher_baseline_.end() ? now : counters_since(now, it->second));
}

}  // namespace hystloop
