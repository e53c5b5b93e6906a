#pragma once
// The logger's handoff from the receiving thread to the disk thread: one preallocated
// byte ring holding variable-length records (a message's bytes plus its channel index
// and receive time), single producer, single consumer. try_push never blocks, locks or
// allocates: a full ring refuses and the caller counts the drop. A record is never split
// across the end of the buffer (a padding marker skips the tail), so the consumer reads
// every payload in place, contiguous.
//
// Sized in bytes, not messages: a 480-byte HX_SENSOR block of 10 ticks costs 504 bytes and
// its 246-byte HX_COMMAND answer 272, so 64 MiB holds ~85 s of both at 10 kHz of ticks in
// blocks of 10 while the disk is stalled.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>

namespace hystloop {

class RecordRing {
 public:
  enum class PushResult { kOk, kFull, kTooLarge };

  struct Record {
    std::uint32_t channel;     // the producer's channel index
    std::int64_t recv_utime;   // [us since the epoch]
    const std::uint8_t* data;  // valid until the consumer's callback returns
    std::size_t size;          // [bytes]
  };

  // `capacity_bytes` is rounded up to a multiple of 8 and must be >= 4096; every page is
  // touched here so the receive path takes no page fault. Throws ParameterError("queue_bytes") outside [4096, 2^31].
  explicit RecordRing(std::size_t capacity_bytes);

  // Producer side.
  PushResult try_push(std::uint32_t channel, std::int64_t recv_utime, const void* data, std::size_t size) noexcept;

  // Consumer side: calls fn(const Record&) for up to `max_records` records in order, each
  // released after its call. Returns how many were passed on.
  template <class Fn>
  std::size_t drain(Fn&& fn, std::size_t max_records = SIZE_MAX) noexcept(noexcept(fn(std::declval<const Record&>())));

  // Bytes the largest record may carry (a quarter of the capacity).
  std::size_t max_payload_bytes() const noexcept { return capacity_ / 4 - kHeaderBytes; }
  std::size_t capacity_bytes() const noexcept { return capacity_; }
  // Bytes in use now (either side may call; approximate while the other side runs).
  std::size_t used_bytes() const noexcept {
    return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
  }
  bool empty() const noexcept { return used_bytes() == 0; }

 private:
  struct Header {
    std::uint32_t total;  // bytes this record occupies, header and padding included
    std::uint32_t size;   // payload bytes, or kPadding for a skip-to-start marker
    std::int64_t recv_utime;
    std::uint32_t channel;
    std::uint32_t reserved;
  };
  static constexpr std::size_t kHeaderBytes = sizeof(Header);
  static constexpr std::uint32_t kPadding = 0xFFFFFFFFu;
  static_assert(kHeaderBytes % 8 == 0);

  std::size_t capacity_;
  std::unique_ptr<std::uint8_t[]> buffer_;
  alignas(64) std::atomic<std::size_t> head_{0};  // bytes ever written (producer)
  alignas(64) std::atomic<std::size_t> tail_{0};  // bytes ever released (consumer)
};

template <class Fn>
std::size_t RecordRing::drain(Fn&& fn, std::size_t max_records) noexcept(noexcept(fn(std::declval<const Record&>()))) {
  std::size_t tail = tail_.load(std::memory_order_relaxed);
  const std::size_t head = head_.load(std::memory_order_acquire);
  std::size_t passed = 0;
  while (tail != head && passed < max_records) {
    const std::uint8_t* at = buffer_.get() + tail % capacity_;
    std::uint32_t total = 0;
    std::uint32_t size = 0;
    std::memcpy(&total, at, sizeof total);
    std::memcpy(&size, at + sizeof total, sizeof size);
    if (size != kPadding) {
      Header h{};
      std::memcpy(&h, at, kHeaderBytes);
      fn(Record{h.channel, h.recv_utime, at + kHeaderBytes, h.size});
      ++passed;
    }
    tail += total;
    tail_.store(tail, std::memory_order_release);
  }
  return passed;
}

}  // namespace hystloop
