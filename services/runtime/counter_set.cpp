#include "runtime/counter_set.hpp"

#include <cstddef>

namespace hystloop {
namespace {

// What counted since the baseline `base` (taken at RESET_COUNTERS).
EndpointCounters counters_since(const EndpointCounters& now, const EndpointCounters& base) noexcept {
  EndpointCounters d;
  d.received = now.received - base.received;
  d.accepted = now.accepted - base.accepted;
  for (std::size_t i = 0; i < kRejectReasonCount; ++i) {
    d.rejected_by_reason[i] = now.rejected_by_reason[i] - base.rejected_by_reason[i];
  }
  return d;
}

PublisherCounters counters_since(const PublisherCounters& now, const PublisherCounters& base) noexcept {
  PublisherCounters d;
  d.published = now.published - base.published;
  d.invalid = now.invalid - base.invalid;
  d.encode_failed = now.encode_failed - base.encode_failed;
  d.transport_failed = now.transport_failed - base.transport_failed;
  return d;
}

}  // namespace

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
