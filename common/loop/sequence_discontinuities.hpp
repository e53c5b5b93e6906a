#pragma once
// Where the sensor ticks went when SequenceGuard confirmed a jump or a restart: the tick the old
// stream expected next, and the first tick of the new numbering, from which the stream continues
// (its first SequenceGuard::kConfirmBlocks - 1 blocks were held, not used, until the last one
// confirmed it). What the compensator's "jumped ahead" and "bridge restart" lines say; the
// last jump and the last restart are kept apart, so that both lines are right when both happened
// within one report period. Nothing here reads a clock, allocates or throws (the sensor path).

#include <cstdint>

#include "loop/sequence_guard.hpp"

namespace hystloop {

struct Discontinuity {
  std::int64_t expected_tick = -1;  // the old stream's next tick (-1: none yet)
  std::int64_t resumed_tick = -1;   // the first tick of the new numbering
};

class SequenceDiscontinuities {
 public:
  // guard.check(seq, n_ticks, now_us), noting where a discontinuity it confirms left from and went to.
  SequenceGuard::Verdict check(SequenceGuard& guard, std::int64_t seq, std::int64_t n_ticks,
                               std::int64_t now_us) noexcept;

  const Discontinuity& last_jump() const noexcept { return jump_; }
  const Discontinuity& last_restart() const noexcept { return restart_; }

 private:
  std::int64_t candidate_first_ = -1;  // first tick of the numbering the guard holds blocks of
  Discontinuity jump_;
  Discontinuity restart_;
};

}  // namespace hystloop
