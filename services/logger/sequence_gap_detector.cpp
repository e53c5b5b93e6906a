#include "logger/sequence_gap_detector.hpp"

#include <string>

#include "core/errors.hpp"

namespace hystloop {

SequenceGapDetector::SequenceGapDetector(std::int64_t restart_threshold) : restart_threshold_(restart_threshold) {
  if (restart_threshold < 1) {
    throw ParameterError("restart_threshold", "must be >= 1 (got " + std::to_string(restart_threshold) + ")");
  }
}

SequenceGapDetector::Outcome SequenceGapDetector::observe(std::int64_t seq) noexcept {
  if (observed_++ == 0) {
    first_ = last_ = seq;
    return Outcome::kFirst;
  }
  // Differences in unsigned arithmetic: well defined for any pair of int64 values.
  const auto useq = static_cast<std::uint64_t>(seq);
  const auto ulast = static_cast<std::uint64_t>(last_);
  if (seq > last_) {
    const std::uint64_t step = useq - ulast;
    if (step > 1) {
      ++gap_events_;
      missing_ += step - 1;
      if (kept_ < kKeptGaps) gaps_[kept_++] = SequenceGap{last_ + 1, seq - 1};
    }
    last_ = seq;
    return step > 1 ? Outcome::kGap : Outcome::kInOrder;
  }
  if (seq == last_) {
    ++duplicates_;
    return Outcome::kDuplicate;
  }
  if (ulast - useq > static_cast<std::uint64_t>(restart_threshold_)) {
    ++restarts_;
    last_ = seq;
    return Outcome::kRestart;
  }
  ++out_of_order_;
  return Outcome::kOutOfOrder;
}

}  // namespace hystloop
