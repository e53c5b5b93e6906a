#pragma once
// Watches the tick numbers (`seq`) of one channel that counts +1 per message
// (HX_SENSOR, HX_COMMAND) and says what each new one means: in order, after a gap of
// missed ticks, a duplicate, late (out of order), or the sender restarted its count.
// Pure logic: no clock, no I/O, no allocation; observe() is on the logger's receive path.
//
//   expected = last + 1
//   seq == expected              in order
//   seq >  expected              a gap: seq - expected ticks missing, [expected, seq - 1]
//   seq == last                  duplicate (last is kept)
//   last - threshold <= seq < last   out of order (a late arrival; last is kept, and the
//                                    gap it may fill stays counted as missing)
//   seq <  last - threshold      restart (the sender began counting again; no gap counted)

#include <array>
#include <cstddef>
#include <cstdint>

namespace hystloop {

// One run of missing ticks, inclusive on both ends.
struct SequenceGap {
  std::int64_t first_missing = 0;
  std::int64_t last_missing = 0;
  std::uint64_t count() const noexcept {
    return static_cast<std::uint64_t>(last_missing) - static_cast<std::uint64_t>(first_missing) + 1;
  }
};

class SequenceGapDetector {
 public:
  enum class Outcome { kFirst, kInOrder, kGap, kDuplicate, kOutOfOrder, kRestart };

  // The first gaps are kept (ranges for the summary); later ones are only counted.
  static constexpr std::size_t kKeptGaps = 8;

  // `restart_threshold` [ticks]: a step back by more than this is a restart, not a late
  // message. Throws ParameterError("restart_threshold") if < 1.
  explicit SequenceGapDetector(std::int64_t restart_threshold = 10000);

  Outcome observe(std::int64_t seq) noexcept;

  std::uint64_t observed() const noexcept { return observed_; }
  std::uint64_t gap_events() const noexcept { return gap_events_; }
  std::uint64_t missing() const noexcept { return missing_; }  // ticks never seen in order
  std::uint64_t duplicates() const noexcept { return duplicates_; }
  std::uint64_t out_of_order() const noexcept { return out_of_order_; }
  std::uint64_t restarts() const noexcept { return restarts_; }
  bool started() const noexcept { return observed_ > 0; }
  std::int64_t first_seq() const noexcept { return first_; }  // meaningful once started()
  std::int64_t last_seq() const noexcept { return last_; }    // highest in-order seq since the last restart

  // The first min(gap_events, kKeptGaps) gaps, in the order seen.
  std::size_t kept_gap_count() const noexcept { return kept_; }
  const std::array<SequenceGap, kKeptGaps>& kept_gaps() const noexcept { return gaps_; }

 private:
  std::int64_t restart_threshold_;
  std::int64_t first_ = 0;
  std::int64_t last_ = 0;
  std::uint64_t observed_ = 0;
  std::uint64_t gap_events_ = 0;
  std::uint64_t missing_ = 0;
  std::uint64_t duplicates_ = 0;
  std::uint64_t out_of_order_ = 0;
  std::uint64_t restarts_ = 0;
  std::array<SequenceGap, kKeptGaps> gaps_{};
  std::size_t kept_ = 0;
};

}  // namespace hystloop
