#pragma once
// Watches the ticks the blocks of one channel cover (HX_SENSOR, HX_COMMAND: a block covers
// ticks seq .. seq + n_ticks - 1, and the next one should start right after it) and says
// what each new block means, counting in ticks. The one tracker of tick numbering: the logger
// feeds it blocks, the compensator and the re-identifier one tick at a time (a tick is a block
// of one); SequenceGuard (loop/) decides whether the compensator believes a block, not what was
// lost. Pure logic: no clock (the caller passes the receive time), no I/O, no allocation, so
// observe() may sit on a receive or a per-sample path.
//
//   L = highest tick seen since the last restart, P = first tick of the block that set it;
//   a new block covers [first, last]:
//   first == L + 1             in order
//   first >  L + 1             a gap: first - L - 1 ticks missing, [L + 1, first - 1] --
//                              or a resume when resume_silence_us > 0 and the channel had been
//                              silent that long (a sender that stalled or restarted and then
//                              started later on purpose, as the compensator does: its commands
//                              run ahead of the bridge's clock): counted apart, as skipped ticks
//   L - first > threshold      restart (the sender began counting again; no gap counted);
//                              threshold 0: every step back is one, kNeverRestarts: none is
//   first <= L < last          overlap: ticks first..L seen again (counted), then in order
//   [first, last] == [P, L]    duplicate of the last block (L kept)
//   otherwise (last <= L)      out of order: a late or repeated block; L is kept, and the gap
//                              it may fill stays counted as missing
//
// The ticks come off the wire, so anyone can forge them. A block the channel contract forbids
// (lcmtypes/sensor_block_t.lcm, command_block_t.lcm; common/lcm/message_checks.hpp) is counted
// as a contract violation by its reason and not fed into the arithmetic above (nor into
// observed(), ticks() or the silence before a resume):
//   negative_seq   seq < 0
//   seq_above_max  seq > kMaxTick (2^53): this is also what rules out seq + n_ticks overflowing
//                  int64, and it bounds every jump: no gap between two admitted blocks is
//                  longer than the tick range the contract documents
//   tick_count     n_ticks outside 1..MAX_TICKS (1000)
// Within the contract the differences are still taken in unsigned arithmetic, and every
// counter saturates at UINT64_MAX instead of wrapping (many gaps of 2^53 ticks add up).

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>

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
  enum class Outcome { kFirst, kInOrder, kGap, kResume, kOverlap, kDuplicate, kOutOfOrder, kRestart, kViolation };
  // Why a block was a contract violation (see above).
  enum class Violation : std::uint8_t { kNegativeSeq, kSeqAboveMax, kTickCount };
  static constexpr std::size_t kViolationKinds = 3;
  static const char* to_string(Violation reason) noexcept;  // "negative_seq", "seq_above_max", "tick_count"

  // The first gaps are kept (ranges for the summary); later ones are only counted.
  static constexpr std::size_t kKeptGaps = 8;

  // A stream whose restarts someone else detects (the compensator's SequenceGuard).
  static constexpr std::int64_t kNeverRestarts = std::numeric_limits<std::int64_t>::max();

  // `restart_threshold` [ticks]: a step back by more than this is a restart, not a late
  // block. `resume_silence_us` [us]: a forward jump after at least this long without a block
  // is a resume, not a gap (0 = every jump is a gap). Throws ParameterError naming the
  // field if restart_threshold < 0 or resume_silence_us < 0.
  explicit SequenceGapDetector(std::int64_t restart_threshold = 10000, std::int64_t resume_silence_us = 0);

  // A block of `n_ticks` from tick `first`, received at `recv_utime` [us] (only compared with
  // the previous block's, for resumes). kViolation (counted, nothing else changes) when the
  // contract forbids the block.
  Outcome observe(std::int64_t first, std::int64_t n_ticks, std::int64_t recv_utime = 0) noexcept;

  std::uint64_t observed() const noexcept { return observed_; }  // blocks within the contract
  std::uint64_t ticks() const noexcept { return ticks_; }        // ticks in those blocks
  std::uint64_t gap_events() const noexcept { return gap_events_; }
  std::uint64_t missing() const noexcept { return missing_; }  // ticks never seen in order
  std::uint64_t resumes() const noexcept { return resumes_; }
  std::uint64_t skipped() const noexcept { return skipped_; }  // ticks jumped over by resumes
  std::uint64_t overlaps() const noexcept { return overlaps_; }
  std::uint64_t overlap_ticks() const noexcept { return overlap_ticks_; }  // ticks seen again by overlaps
  std::uint64_t duplicates() const noexcept { return duplicates_; }
  std::uint64_t out_of_order() const noexcept { return out_of_order_; }
  std::uint64_t restarts() const noexcept { return restarts_; }
  std::uint64_t violations(Violation reason) const noexcept { return violations_[static_cast<std::size_t>(reason)]; }
  std::uint64_t violations() const noexcept;  // all reasons
  bool started() const noexcept { return observed_ > 0; }
  std::int64_t first_seq() const noexcept { return first_; }  // meaningful once started()
  std::int64_t last_seq() const noexcept { return last_; }    // highest tick in order since the last restart

  // The first min(gap_events, kKeptGaps) gaps, in the order seen.
  std::size_t kept_gap_count() const noexcept { return kept_; }
  const std::array<SequenceGap, kKeptGaps>& kept_gaps() const noexcept { return gaps_; }

 private:
  void advance(std::int64_t first, std::int64_t last) noexcept {
    block_first_ = first;
    last_ = last;
  }

  std::int64_t restart_threshold_;
  std::int64_t resume_silence_us_;
  std::int64_t first_ = 0;
  std::int64_t last_ = 0;
  std::int64_t block_first_ = 0;
  std::int64_t last_utime_ = 0;
  std::uint64_t observed_ = 0;
  std::uint64_t ticks_ = 0;
  std::uint64_t gap_events_ = 0;
  std::uint64_t missing_ = 0;
  std::uint64_t resumes_ = 0;
  std::uint64_t skipped_ = 0;
  std::uint64_t overlaps_ = 0;
  std::uint64_t overlap_ticks_ = 0;
  std::uint64_t duplicates_ = 0;
  std::uint64_t out_of_order_ = 0;
  std::uint64_t restarts_ = 0;
  std::array<std::uint64_t, kViolationKinds> violations_{};
  std::array<SequenceGap, kKeptGaps> gaps_{};
  std::size_t kept_ = 0;
};

}  // namespace hystloop
