#pragma once
// Whether a sensor block's tick numbers (seq .. seq + n - 1) are believed. A block that
// continues the stream (its first tick within max_step ticks of the next expected one, either
// way) is taken at once: lost blocks and small reorders are the compensator's to count. A block
// further away is a discontinuity: a bridge restarted (seq far behind) or skipped (far ahead),
// or a forged/corrupted block. One block proves nothing, so it is held (not used) until
// kConfirmBlocks consecutive blocks continue ITS numbering, each within confirm_window_us of the
// previous one:
//   - the kConfirmBlocks-th one confirms it: `restart` (behind) or `jump` (ahead), used from there;
//   - a block that continues the old stream before that drops it: the discontinuity is ignored
//     (counted) and that block is taken as usual; so is a block arriving after the window;
//   - a block far from both starts a new candidate (the old one is ignored).
// kConfirmBlocks = 3: a forger or a corrupted datagram must produce three consistent blocks in a
// row with no real block between (the bridge sends one every block period, 2 ms at 20 ticks),
// while a real restart costs only the two blocks held before the third confirms (4 ms of samples
// at 20 ticks per block; the restarted bridge starts in its safe state and needs no command yet).
// Time is an argument (the compensator passes the block's sample time, sensor_block_t.utime, so
// that its commands stay a function of the messages); nothing here reads a clock, allocates or throws.

#include <cstdint>

namespace hystloop {

class SequenceGuard {
 public:
  static constexpr int kConfirmBlocks = 3;

  enum class Verdict : std::uint8_t {
    take,     // continues the stream (or the first block): use it
    hold,     // a discontinuity not confirmed yet: do not use it
    jump,     // confirms a jump ahead: use it (the ticks between are missed)
    restart,  // confirms a restart (numbering went back): restart the control law, then use it
  };

  struct Counters {
    std::uint64_t held = 0;      // blocks held (not used) while a discontinuity was unconfirmed
    std::uint64_t ignored = 0;   // discontinuities never confirmed
    std::uint64_t jumps = 0;     // confirmed jumps ahead
    std::uint64_t restarts = 0;  // confirmed restarts
  };

  // max_step_ticks: how far from the next expected tick a block may start and still continue the
  // stream (>= 1); confirm_window_us: the most time between two blocks of a candidate.
  SequenceGuard(std::int64_t max_step_ticks, std::int64_t confirm_window_us) noexcept;

  // A block of ticks seq .. seq + n_ticks - 1 (n_ticks >= 1) received at now_us.
  Verdict check(std::int64_t seq, std::int64_t n_ticks, std::int64_t now_us) noexcept;
  void reset() noexcept;  // forget the stream: the next block is taken as the first

  const Counters& counters() const noexcept { return counters_; }
  bool pending() const noexcept { return streak_ > 0; }
  std::int64_t next_expected() const noexcept { return next_; }  // -1 before the first block

 private:
  bool continues(std::int64_t next, std::int64_t seq) const noexcept;

  std::int64_t max_step_;
  std::int64_t window_us_;
  std::int64_t next_ = -1;  // the tick after the last block taken
  int streak_ = 0;          // blocks of the candidate so far (0 = none)
  std::int64_t candidate_next_ = 0;
  std::int64_t candidate_utime_ = 0;
  Counters counters_{};
};

}  // namespace hystloop
