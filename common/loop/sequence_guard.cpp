#include "loop/sequence_guard.hpp"

#include <algorithm>
#include <limits>

namespace hystloop {

SequenceGuard::SequenceGuard(std::int64_t max_step_ticks, std::int64_t confirm_window_us) noexcept
    : max_step_(std::max<std::int64_t>(max_step_ticks, 1)), window_us_(std::max<std::int64_t>(confirm_window_us, 0)) {}

void SequenceGuard::reset() noexcept {
  next_ = -1;
  streak_ = 0;
}

bool SequenceGuard::continues(std::int64_t next, std::int64_t seq) const noexcept {
  // No overflow: seq >= 0 and next <= the last seq + MAX_TICKS on the wire; compare the difference.
  const std::int64_t d = seq >= next ? seq - next : next - seq;
  return d <= max_step_;
}

SequenceGuard::Verdict SequenceGuard::check(std::int64_t seq, std::int64_t n_ticks, std::int64_t now_us) noexcept {
  // Saturating: a forged seq near the int64 ceiling must not overflow (the wire bounds seq >= 0 only).
  const std::int64_t n = std::max<std::int64_t>(n_ticks, 1);
  const std::int64_t end =
      seq > std::numeric_limits<std::int64_t>::max() - n ? std::numeric_limits<std::int64_t>::max() : seq + n;
  if (next_ < 0) {
    next_ = end;
    return Verdict::take;
  }
  if (streak_ > 0) {
    const bool in_time = now_us - candidate_utime_ <= window_us_ && now_us >= candidate_utime_;
    if (in_time && continues(candidate_next_, seq) && !continues(next_, seq)) {
      candidate_next_ = std::max(candidate_next_, end);
      candidate_utime_ = now_us;
      if (++streak_ < kConfirmBlocks) {
        ++counters_.held;
        return Verdict::hold;
      }
      streak_ = 0;
      const bool back = seq < next_;
      next_ = candidate_next_;
      if (back) {
        ++counters_.restarts;
        return Verdict::restart;
      }
      ++counters_.jumps;
      return Verdict::jump;
    }
    streak_ = 0;  // broken: the discontinuity was not confirmed
    ++counters_.ignored;
  }
  if (continues(next_, seq)) {
    next_ = std::max(next_, end);
    return Verdict::take;
  }
  streak_ = 1;
  candidate_next_ = end;
  candidate_utime_ = now_us;
  ++counters_.held;
  return Verdict::hold;
}

}  // namespace hystloop
