#include "lcm/reject_reason.hpp"

#include <numeric>

namespace hystloop {

std::string_view to_string(RejectReason reason) noexcept {
  switch (reason) {
    case RejectReason::kWrongType: return "wrong_type";
    case RejectReason::kDecodeFailed: return "decode_failed";
    case RejectReason::kSizeMismatch: return "size_mismatch";
    case RejectReason::kNonFinite: return "non_finite";
    case RejectReason::kOutOfRange: return "out_of_range";
    case RejectReason::kHandlerFailed: return "handler_failed";
    case RejectReason::kUnsigned: return "unsigned";
    case RejectReason::kBadMac: return "bad_mac";
    case RejectReason::kReplayed: return "replayed";
    case RejectReason::kSkewed: return "skewed";
  }
  return "unknown";
}

std::uint64_t EndpointCounters::rejected_total() const noexcept {
  return std::accumulate(rejected_by_reason.begin(), rejected_by_reason.end(), std::uint64_t{0});
}

}  // namespace hystloop
