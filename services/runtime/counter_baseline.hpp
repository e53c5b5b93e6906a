#pragma once
// RESET_COUNTERS without touching the counters themselves (they only count up, and some
// belong to another thread): a service keeps a copy taken at the reset and reports the
// difference. Off the per-sample path.

#include <cstddef>

#include "lcm/reject_reason.hpp"

namespace hystloop {

inline EndpointCounters counters_since(const EndpointCounters& now, const EndpointCounters& base) noexcept {
  EndpointCounters d;
  d.received = now.received - base.received;
  d.accepted = now.accepted - base.accepted;
  for (std::size_t i = 0; i < kRejectReasonCount; ++i) {
    d.rejected_by_reason[i] = now.rejected_by_reason[i] - base.rejected_by_reason[i];
  }
  return d;
}

inline PublisherCounters counters_since(const PublisherCounters& now, const PublisherCounters& base) noexcept {
  PublisherCounters d;
  d.published = now.published - base.published;
  d.invalid = now.invalid - base.invalid;
  d.encode_failed = now.encode_failed - base.encode_failed;
  d.transport_failed = now.transport_failed - base.transport_failed;
  return d;
}

}  // namespace hystloop
