#pragma once
// The parameter version HX_COMMAND carries, by tick: which version the compensator's
// feedforward came from at a given sensor tick. Commands arrive up to a horizon (tens of ms)
// ahead of the bridge's clock, so the last block received describes ticks not sampled yet:
// the version at a sample is that of the latest command tick AT OR BEFORE the sample's tick
// (the bridge holds the last command when a tick has none, so that also covers late ticks).
//
// Versions change rarely (at a refit, and only at a reversal), so the timeline keeps change
// points (first tick, version) in a fixed ring: no allocation, a handful of entries in use.
//
//   record(seq, version)   each command tick, in arrival order
//   at(seq)                version of the latest recorded tick <= seq; kUnknown if none
//   forget_before(seq)     drops change points that no sample at or after seq needs
//
// The newest plan wins: a command for tick s replaces whatever was recorded for ticks >= s.
// With each tick sent once and in order (the compensator's contract) that is exact, and it
// makes a restarted tick numbering (a bridge restart: commands for low ticks again) replace
// the old one at once. A block reordered in transit across a version change leaves the ticks
// of the blocks it overtook at the older version until the next block arrives.
// A full ring drops its oldest change point (counted: overflows()).

#include <array>
#include <cstddef>
#include <cstdint>

namespace hystloop {

class VersionTimeline {
 public:
  static constexpr std::size_t kCapacity = 64;
  static constexpr std::int32_t kUnknown = -1;

  void record(std::int64_t seq, std::int32_t version) noexcept;
  std::int32_t at(std::int64_t seq) const noexcept;
  void forget_before(std::int64_t seq) noexcept;
  void clear() noexcept { size_ = 0; }

  std::size_t size() const noexcept { return size_; }
  std::uint64_t overflows() const noexcept { return overflows_; }

 private:
  struct Change {
    std::int64_t seq = 0;  // first tick with this version
    std::int32_t version = 0;
  };
  // i-th change point from the oldest, i < size_.
  Change& entry(std::size_t i) noexcept { return ring_[(head_ + i) % kCapacity]; }
  const Change& entry(std::size_t i) const noexcept { return ring_[(head_ + i) % kCapacity]; }

  std::array<Change, kCapacity> ring_{};
  std::size_t head_ = 0;  // index of the oldest
  std::size_t size_ = 0;
  std::uint64_t overflows_ = 0;
};

}  // namespace hystloop
