#pragma once
// Channels the logger has no slot for (its table is full, or the name is longer than LCM
// allows): counted in bounded memory, never recorded. Junk traffic with thousands of names
// then costs a hash probe per message and cannot push the rig's channels out.
//
// Counts: messages, distinct names (exact up to kTrackedNames, then a lower bound:
// distinct_is_lower_bound()), and the first kKeptNames names (cut to kMaxName bytes) for
// the status and the summary. Receiving thread only; no allocation.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace hystloop {

class UnknownChannels {
 public:
  static constexpr std::size_t kTrackedNames = 2048;  // distinct names counted exactly
  static constexpr std::size_t kKeptNames = 8;
  static constexpr std::size_t kMaxName = 63;

  // One message on channel `name` (`length` bytes).
  void count(const char* name, std::size_t length) noexcept;

  std::uint64_t messages() const noexcept { return messages_; }
  std::uint64_t distinct() const noexcept { return distinct_; }
  bool distinct_is_lower_bound() const noexcept { return saturated_; }
  std::size_t kept_count() const noexcept { return kept_; }
  std::string_view kept_name(std::size_t i) const noexcept { return {names_[i].data(), lengths_[i]}; }

 private:
  static constexpr std::size_t kHashSlots = 2 * kTrackedNames;  // open addressing, at most half full

  std::array<std::uint64_t, kHashSlots> hashes_{};  // 0 = empty
  std::uint64_t messages_ = 0;
  std::uint64_t distinct_ = 0;
  bool saturated_ = false;
  std::array<std::array<char, kMaxName>, kKeptNames> names_{};
  std::array<std::size_t, kKeptNames> lengths_{};
  std::size_t kept_ = 0;
};

}  // namespace hystloop
