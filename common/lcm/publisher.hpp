#pragma once
// A typed LCM publisher that checks a message against the contract before it leaves the
// process and encodes it into a buffer it keeps: publishing a fixed-size type allocates
// nothing in this class (the buffer grows only for a variable-size message larger than any
// before). Failures are counted and returned, never thrown. Not thread-safe: one
// Publisher per publishing thread (lcm::LCM itself may be shared).

#include <climits>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "lcm/message_checks.hpp"
#include "lcm/message_storage.hpp"
#include "lcm/reject_reason.hpp"

namespace hystloop {

template <class T>
class Publisher {
 public:
  // `check` nullptr publishes without checking values (tests of receivers do that).
  Publisher(lcm::LCM& lcm, std::string channel, MessageCheck<T> check = default_message_check<T>())
      : lcm_(lcm), channel_(std::move(channel)), check_(check) {
    const T empty{};
    buffer_.resize(static_cast<std::size_t>(empty.getEncodedSize()));
  }

  // Returns true if the message was handed to LCM.
  bool publish(const T& msg) noexcept {
    if (check_ != nullptr && check_(msg) != Verdict::kOk) {
      ++counters_.invalid;
      return false;
    }
    if (!arrays_consistent(msg)) {
      ++counters_.encode_failed;
      return false;
    }
    const int size = msg.getEncodedSize();
    if (size <= 0) {
      ++counters_.encode_failed;
      return false;
    }
    if (static_cast<std::size_t>(size) > buffer_.size()) {
      try {
        buffer_.resize(static_cast<std::size_t>(size));
      } catch (...) {
        ++counters_.encode_failed;
        return false;
      }
    }
    if (msg.encode(buffer_.data(), 0, size) != size) {
      ++counters_.encode_failed;
      return false;
    }
    if (lcm_.publish(channel_, buffer_.data(), static_cast<unsigned int>(size)) != 0) {
      ++counters_.transport_failed;
      return false;
    }
    ++counters_.published;
    return true;
  }

  const PublisherCounters& counters() const noexcept { return counters_; }
  const std::string& channel() const noexcept { return channel_; }

 private:
  lcm::LCM& lcm_;
  std::string channel_;
  MessageCheck<T> check_;
  std::vector<std::uint8_t> buffer_;
  PublisherCounters counters_;
};

}  // namespace hystloop
