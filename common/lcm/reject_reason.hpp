#pragma once
// Why a received message was not delivered, and the counts an endpoint keeps of it.
// Services publish these counts in service_status_t (see status_counters.hpp).

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace hystloop {

enum class RejectReason : std::uint8_t {
  kWrongType,      // the fingerprint is another type's: something else publishes on this channel
  kDecodeFailed,   // truncated, a length field that does not fit the buffer, or lcm decode < 0
  kSizeMismatch,   // decoded fine but used fewer bytes than were received (trailing garbage)
  kNonFinite,      // a NaN/Inf where the contract wants a number
  kOutOfRange,     // a value outside the contract (negative seq, unknown enum, c3 <= 0, ...)
  kHandlerFailed,  // the message was valid but the handler threw
  // A keyed rig's authenticated channels (lcm/rig_auth.hpp):
  kUnsigned,  // no authentication trailer
  kBadMac,    // the MAC does not match: altered, moved from another channel, or another key
  kReplayed,  // counter not above the last one accepted from its sender (a repeat or a replay)
  kSkewed,    // counter further than auth.max_skew_s from this host's clock (a recording, or clocks apart)
};
inline constexpr std::size_t kRejectReasonCount = 10;

// "wrong_type", "decode_failed", "size_mismatch", "non_finite", "out_of_range", "handler_failed",
// "unsigned", "bad_mac", "replayed", "skewed".
std::string_view to_string(RejectReason reason) noexcept;

// What a per-type value check says about a decoded message.
enum class Verdict : std::uint8_t { kOk, kNonFinite, kOutOfRange };

struct EndpointCounters {
  std::uint64_t received = 0;  // every message the transport delivered
  std::uint64_t accepted = 0;  // decoded, valid, and handled without exception
  std::array<std::uint64_t, kRejectReasonCount> rejected_by_reason{};

  std::uint64_t rejected(RejectReason reason) const noexcept {
    return rejected_by_reason[static_cast<std::size_t>(reason)];
  }
  std::uint64_t rejected_total() const noexcept;
  void count(RejectReason reason) noexcept { ++rejected_by_reason[static_cast<std::size_t>(reason)]; }
};

struct PublisherCounters {
  std::uint64_t published = 0;
  std::uint64_t invalid = 0;           // refused by the value check before encoding: never sent
  std::uint64_t encode_failed = 0;     // encode < 0, or the buffer could not grow
  std::uint64_t transport_failed = 0;  // lcm publish returned an error
};

}  // namespace hystloop
