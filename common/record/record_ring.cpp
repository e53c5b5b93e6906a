#include "record/record_ring.hpp"

#include <string>

#include "core/errors.hpp"

namespace hystloop {

namespace {
constexpr std::size_t align8(std::size_t n) noexcept { return (n + 7) & ~static_cast<std::size_t>(7); }
}  // namespace

RecordRing::RecordRing(std::size_t capacity_bytes) : capacity_(align8(capacity_bytes)) {
  if (capacity_bytes < 4096 || capacity_bytes > (std::size_t{1} << 31)) {
    throw ParameterError("queue_bytes", "must be in [4096, 2^31] (got " + std::to_string(capacity_bytes) + ")");
  }
  buffer_ = std::make_unique<std::uint8_t[]>(capacity_);  // value-initialised: every page touched
}

RecordRing::PushResult RecordRing::try_push(std::uint32_t channel, std::int64_t recv_utime, const void* data,
                                            std::size_t size) noexcept {
  if (size > max_payload_bytes()) return PushResult::kTooLarge;
  const std::size_t need = align8(kHeaderBytes + size);
  const std::size_t head = head_.load(std::memory_order_relaxed);
  const std::size_t tail = tail_.load(std::memory_order_acquire);
  const std::size_t pos = head % capacity_;
  const std::size_t to_end = capacity_ - pos;  // >= 8: every record is a multiple of 8
  const std::size_t pad = need > to_end ? to_end : 0;
  if (head + pad + need - tail > capacity_) return PushResult::kFull;

  if (pad > 0) {
    const auto total = static_cast<std::uint32_t>(pad);
    std::memcpy(buffer_.get() + pos, &total, sizeof total);
    std::memcpy(buffer_.get() + pos + sizeof total, &kPadding, sizeof kPadding);
  }
  std::uint8_t* at = buffer_.get() + (head + pad) % capacity_;
  const Header h{static_cast<std::uint32_t>(need), static_cast<std::uint32_t>(size), recv_utime, channel, 0};
  std::memcpy(at, &h, kHeaderBytes);
  if (size > 0) std::memcpy(at + kHeaderBytes, data, size);
  head_.store(head + pad + need, std::memory_order_release);
  return PushResult::kOk;
}

}  // namespace hystloop
