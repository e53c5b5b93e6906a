#pragma once
// Decoding one logged message the way a Subscription does: the fingerprint is T's, every
// length field fits the buffer (checked before lcm-gen's decode trusts it), the whole
// buffer is used, and the values pass the contract's check. A corrupt event in a log is
// then a count, never a crash or a gigabyte allocation.

#include <cstdint>

#include <lcm/lcm-cpp.hpp>

#include "lcm/message_checks.hpp"
#include "lcm/message_storage.hpp"
#include "lcm/rig_auth.hpp"
#include "lcm/wire_layout.hpp"

namespace hystloop::report {

// True if `data` starts with T's fingerprint (decides a channel's type from its bytes).
template <class T>
bool has_fingerprint_of(const lcm::LogEvent& event) noexcept {
  if (event.datalen < 8) return false;
  const auto size = static_cast<std::size_t>(event.datalen);
  return wire_fingerprint(event.data, size) == T::getHash();
}

// `event` decoded as T the way a Subscription decodes it (fingerprint, length fields, whole buffer
// used), without the contract's value check: for a caller that treats a value out of contract
// differently from a message that does not decode (hystloop-identify refuses a non-finite sample
// but counts a corrupt block). The arrays of a message that decodes hold their counts.
template <class T>
bool decode_unchecked(const lcm::LogEvent& event, T& msg) noexcept {
  if (!has_fingerprint_of<T>(event)) return false;
  const auto size = static_cast<std::size_t>(event.datalen);
  const std::int64_t body = lcm_body_size(wire_layout_of<T>(), event.data, size);  // a signed message's trailer ignored
  if (body < 0) return false;
  clear_arrays(msg);
  try {
    return msg.decode(event.data, 0, static_cast<int>(body)) == static_cast<int>(body);
  } catch (...) {
    return false;
  }
}

// decode_unchecked, and the values pass the contract's check.
template <class T>
bool decode_checked(const lcm::LogEvent& event, T& msg) noexcept {
  return decode_unchecked(event, msg) && check_message(msg) == Verdict::kOk;
}

}  // namespace hystloop::report
