#include "record/unknown_channels.hpp"

#include <cstring>

namespace hystloop {

namespace {
std::uint64_t fnv1a(const char* text, std::size_t length) noexcept {
  std::uint64_t h = 14695981039346656037ull;
  for (std::size_t i = 0; i < length; ++i) {
    h ^= static_cast<unsigned char>(text[i]);
    h *= 1099511628211ull;
  }
  return h == 0 ? 1 : h;  // 0 marks an empty slot
}
}  // namespace

void UnknownChannels::count(const char* name, std::size_t length) noexcept {
  if (messages_ < UINT64_MAX) ++messages_;
  const std::uint64_t h = fnv1a(name, length);
  for (std::size_t probe = 0, i = h % kHashSlots; probe < kHashSlots; ++probe, i = (i + 1) % kHashSlots) {
    if (hashes_[i] == h) return;  // seen before
    if (hashes_[i] != 0) continue;
    if (distinct_ >= kTrackedNames) {  // full: new names are still counted, as a lower bound
      saturated_ = true;
      return;
    }
    hashes_[i] = h;
    ++distinct_;
    if (kept_ < kKeptNames) {
      lengths_[kept_] = length < kMaxName ? length : kMaxName;
      std::memcpy(names_[kept_].data(), name, lengths_[kept_]);
      ++kept_;
    }
    return;
  }
}

}  // namespace hystloop
