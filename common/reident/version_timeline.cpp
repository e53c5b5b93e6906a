#include "reident/version_timeline.hpp"

namespace hystloop {

void VersionTimeline::record(std::int64_t seq, std::int32_t version) noexcept {
  while (size_ > 0 && entry(size_ - 1).seq >= seq) --size_;  // the newest plan wins
  if (size_ > 0 && entry(size_ - 1).version == version) return;
  if (size_ == kCapacity) {
    head_ = (head_ + 1) % kCapacity;
    --size_;
    ++overflows_;
  }
  entry(size_) = Change{seq, version};
  ++size_;
}

std::int32_t VersionTimeline::at(std::int64_t seq) const noexcept {
  for (std::size_t i = size_; i > 0; --i) {
    if (entry(i - 1).seq <= seq) return entry(i - 1).version;
  }
  return kUnknown;
}

void VersionTimeline::forget_before(std::int64_t seq) noexcept {
  while (size_ >= 2 && entry(1).seq <= seq) {
    head_ = (head_ + 1) % kCapacity;
    --size_;
  }
}

}  // namespace hystloop
