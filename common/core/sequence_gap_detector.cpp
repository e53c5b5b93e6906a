#include "core/sequence_gap_detector.hpp"

#include <optional>
#include <string>

#include "core/errors.hpp"
#include "core/saturating.hpp"
#include "core/ticks.hpp"

namespace hystloop {

namespace {
std::optional<SequenceGapDetector::Violation> contract_violation(std::int64_t first, std::int64_t n_ticks) noexcept {
  using V = SequenceGapDetector::Violation;
  if (first < 0) return V::kNegativeSeq;
  if (first > kMaxTick) return V::kSeqAboveMax;
  if (n_ticks < 1 || n_ticks > kMaxBlockTicks) return V::kTickCount;
  return std::nullopt;
}
}  // namespace

const char* SequenceGapDetector::to_string(Violation reason) noexcept {
  switch (reason) {
    case Violation::kNegativeSeq: return "negative_seq";
    case Violation::kSeqAboveMax: return "seq_above_max";
    case Violation::kTickCount: return "tick_count";
  }
  return "unknown";
}

std::uint64_t SequenceGapDetector::violations() const noexcept {
  std::uint64_t total = 0;
  for (const std::uint64_t n : violations_) add_saturating(total, n);
  return total;
}

SequenceGapDetector::SequenceGapDetector(std::int64_t restart_threshold, std::int64_t resume_silence_us)
    : restart_threshold_(restart_threshold), resume_silence_us_(resume_silence_us) {
  if (restart_threshold < 0) {
    throw ParameterError("restart_threshold", "must be >= 0 (got " + std::to_string(restart_threshold) + ")");
  }
  if (resume_silence_us < 0) {
    throw ParameterError("resume_silence_us", "must be >= 0 (got " + std::to_string(resume_silence_us) + ")");
  }
}

SequenceGapDetector::Outcome SequenceGapDetector::observe(std::int64_t first, std::int64_t n_ticks,
                                                          std::int64_t recv_utime) noexcept {
  if (const std::optional<Violation> v = contract_violation(first, n_ticks)) {
    add_saturating(violations_[static_cast<std::size_t>(*v)], 1);
    return Outcome::kViolation;
  }
  const std::int64_t last = first + (n_ticks - 1);  // <= 2^53 + 999: no overflow
  const std::int64_t silence_us = recv_utime - last_utime_;
  last_utime_ = recv_utime;
  add_saturating(ticks_, static_cast<std::uint64_t>(n_ticks));
  add_saturating(observed_, 1);
  if (observed_ == 1) {
    first_ = first;
    advance(first, last);
    return Outcome::kFirst;
  }
  // Differences in unsigned arithmetic: well defined for any pair of int64 values.
  const auto ufirst = static_cast<std::uint64_t>(first);
  const auto ulast = static_cast<std::uint64_t>(last_);
  if (first > last_) {
    const std::uint64_t jumped = ufirst - ulast - 1;  // ticks between the blocks
    Outcome outcome = Outcome::kInOrder;
    if (jumped > 0 && resume_silence_us_ > 0 && silence_us >= resume_silence_us_) {
      add_saturating(resumes_, 1);
      add_saturating(skipped_, jumped);
      outcome = Outcome::kResume;
    } else if (jumped > 0) {
      add_saturating(gap_events_, 1);
      add_saturating(missing_, jumped);
      if (kept_ < kKeptGaps) gaps_[kept_++] = SequenceGap{last_ + 1, first - 1};
      outcome = Outcome::kGap;
    }
    advance(first, last);
    return outcome;
  }
  if (ulast - ufirst > static_cast<std::uint64_t>(restart_threshold_)) {
    add_saturating(restarts_, 1);
    advance(first, last);
    return Outcome::kRestart;
  }
  if (last > last_) {
    add_saturating(overlaps_, 1);
    add_saturating(overlap_ticks_, ulast - ufirst + 1);
    advance(first, last);
    return Outcome::kOverlap;
  }
  if (first == block_first_ && last == last_) {
    add_saturating(duplicates_, 1);
    return Outcome::kDuplicate;
  }
  add_saturating(out_of_order_, 1);
  return Outcome::kOutOfOrder;
}

}  // namespace hystloop
