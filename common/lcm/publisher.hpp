#pragma once
// A typed LCM publisher that checks a message against the contract before it leaves the
// process and encodes it into a buffer it keeps: publishing a fixed-size type allocates
// nothing in this class (the buffer grows only for a variable-size message larger than any
// before). Failures are counted and returned, never thrown. Not thread-safe: one
// Publisher per publishing thread (lcm::LCM itself may be shared).
// On a keyed rig's authenticated channel (lcm/rig_auth.hpp) each message is followed by an
// authentication trailer signed with the rig key; the Publisher is then one sender (its own
// random sender id and counter).

#include <climits>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <memory>
#include <optional>

#include <lcm/lcm-cpp.hpp>

#include "auth/message_auth.hpp"
#include "core/clock.hpp"
#include "lcm/message_checks.hpp"
#include "lcm/message_storage.hpp"
#include "lcm/reject_reason.hpp"
#include "lcm/rig_auth.hpp"

namespace hystloop {

template <class T>
class Publisher {
 public:
  // `check` nullptr publishes without checking values (tests of receivers do that).
  // `auth` nullptr (or a channel that is not authenticated) sends unsigned messages.
  Publisher(lcm::LCM& lcm, std::string channel, MessageCheck<T> check = default_message_check<T>(),
            const std::shared_ptr<const RigAuth>& auth = process_rig_auth())
      : lcm_(lcm), channel_(std::move(channel)), check_(check) {
    if (auth != nullptr && is_authenticated_channel(channel_)) signer_.emplace(auth->key);
    const T empty{};
    buffer_.resize(static_cast<std::size_t>(empty.getEncodedSize()) + trailer_size());
  }

  // Returns true if the message was handed to LCM.
  bool publish(const T& msg) noexcept {
    if (check_ != nullptr && check_(msg) != Verdict::kOk) {
      ++counters_.invalid;
      return false;
    }
    // An inconsistent message would be encoded from its counts, reading past its arrays.
    const int size = arrays_consistent(msg) ? msg.getEncodedSize() : 0;
    const std::size_t total = static_cast<std::size_t>(size) + trailer_size();
    if (size <= 0 || total > static_cast<std::size_t>(INT_MAX) || !fits(total) ||
        msg.encode(buffer_.data(), 0, size) != size) {
      ++counters_.encode_failed;
      return false;
    }
    if (signer_) {
      signer_->sign(channel_, buffer_.data(), static_cast<std::size_t>(size), wall_utime(), buffer_.data() + size);
    }
    if (lcm_.publish(channel_, buffer_.data(), static_cast<unsigned int>(total)) != 0) {
      ++counters_.transport_failed;
      return false;
    }
    ++counters_.published;
    return true;
  }

  const PublisherCounters& counters() const noexcept { return counters_; }
  const std::string& channel() const noexcept { return channel_; }
  // True when this publisher signs its messages.
  bool signs() const noexcept { return signer_.has_value(); }

 private:
  std::size_t trailer_size() const noexcept { return signer_ ? kAuthTrailerBytes : 0; }
  // Grows the buffer for a message beyond the size reserved; false when that fails.
  bool fits(std::size_t total) noexcept {
    if (total <= buffer_.size()) return true;
    try {
      buffer_.resize(total);
    } catch (...) {
      return false;
    }
    return true;
  }

  lcm::LCM& lcm_;
  std::string channel_;
  MessageCheck<T> check_;
  std::vector<std::uint8_t> buffer_;
  PublisherCounters counters_;
  std::optional<MessageSigner> signer_;
};

}  // namespace hystloop
