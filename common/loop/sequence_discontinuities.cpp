#include "loop/sequence_discontinuities.hpp"

namespace hystloop {

SequenceGuard::Verdict SequenceDiscontinuities::check(SequenceGuard& guard, std::int64_t seq, std::int64_t n_ticks,
                                                      std::int64_t now_us) noexcept {
  // The old stream's next tick does not move while a candidate is held (a block that continues
  // the old stream drops the candidate), so the value before the confirming block is the one
  // expected when the candidate began.
  const std::int64_t expected = guard.next_expected();
  const bool was_pending = guard.pending();
  const std::uint64_t ignored = guard.counters().ignored;
  const SequenceGuard::Verdict verdict = guard.check(seq, n_ticks, now_us);
  switch (verdict) {
    case SequenceGuard::Verdict::hold:
      // A new candidate: none was pending, or the pending one was just given up for this block.
      if (!was_pending || guard.counters().ignored != ignored) candidate_first_ = seq;
      break;
    case SequenceGuard::Verdict::jump: jump_ = {expected, candidate_first_}; break;
    case SequenceGuard::Verdict::restart: restart_ = {expected, candidate_first_}; break;
    case SequenceGuard::Verdict::take: break;
  }
  return verdict;
}

}  // namespace hystloop
