#pragma once
// When each recent sensor block was handed to LCM, indexed by its last tick, so that the command
// block computed from it (command_block_t.sample_seq) gives the block-to-answer latency.
// Fixed size, allocation-free; an answer older than the ring is not measured.

#include <array>
#include <cstdint>
#include <optional>

namespace hystloop {

class SendTimeRing {
 public:
  static constexpr std::size_t kSize = 4096;  // 0.4 s at 10 kHz

  void record(std::int64_t seq, std::int64_t sent_ns) noexcept {
    Entry& e = entries_[static_cast<std::size_t>(seq) % kSize];
    e.seq = seq;
    e.sent_ns = sent_ns;
  }
  // Time since sample `seq` was sent, if it is still in the ring.
  std::optional<std::int64_t> elapsed_since(std::int64_t seq, std::int64_t now_ns) const noexcept {
    if (seq < 0) return std::nullopt;
    const Entry& e = entries_[static_cast<std::size_t>(seq) % kSize];
    if (e.seq != seq) return std::nullopt;
    return now_ns - e.sent_ns;
  }

 private:
  struct Entry {
    std::int64_t seq = -1;
    std::int64_t sent_ns = 0;
  };
  std::array<Entry, kSize> entries_{};
};

}  // namespace hystloop
