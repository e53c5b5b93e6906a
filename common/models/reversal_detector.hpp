#pragma once
// Detects the direction reversals (branching points) of a sampled signal: the input u for a
// forward model, the reference y_ref for an inverse.
//
// The signal's direction is that of its last change that counted, so a signal that stands still
// (any number of equal samples) never reverses. A reversal is declared when the signal retreats
// from its running extremum by MORE than `deadband` (same unit as the signal); the branching point
// is then that extremum, not the current sample. With the default deadband 0 every move against
// the direction is a reversal at the previous sample: exactly the paper's model. A deadband > 0
// ignores jitter smaller than it, at the price of a small jump when the reversal is finally
// declared (the model moves from the old branch to the new one that starts at the extremum).

#include <cmath>

namespace hystloop {

class ReversalDetector {
 public:
  enum class Event {
    kNone,      // hold, or a retreat within the deadband: the extremum is unchanged
    kExtend,    // moved on in the current direction (or set the first direction): new extremum
    kReversal,  // turned: turning_point() is the branching point; the new extremum is the sample
  };

  explicit ReversalDetector(double deadband = 0.0) noexcept : deadband_(deadband) {}

  // Starts at x0. direction: +1/-1 if the signal is taken to have been moving that way, 0 if
  // unknown (then the first move beyond the deadband sets it without a reversal).
  void reset(double x0, int direction = 0) noexcept {
    extremum_ = x0;
    turning_point_ = x0;
    direction_ = direction > 0 ? 1 : (direction < 0 ? -1 : 0);
  }

  Event update(double x) noexcept {
    if (direction_ == 0) {
      if (std::abs(x - extremum_) > deadband_) {
        direction_ = x > extremum_ ? 1 : -1;
        extremum_ = x;
        return Event::kExtend;
      }
      return Event::kNone;
    }
    const double ahead = direction_ > 0 ? x - extremum_ : extremum_ - x;
    if (ahead > 0.0) {
      extremum_ = x;
      return Event::kExtend;
    }
    if (-ahead > deadband_) {
      turning_point_ = extremum_;
      extremum_ = x;
      direction_ = -direction_;
      return Event::kReversal;
    }
    return Event::kNone;
  }

  int direction() const noexcept { return direction_; }             // +1, -1, or 0 (not yet known)
  double extremum() const noexcept { return extremum_; }            // furthest point in the direction
  double turning_point() const noexcept { return turning_point_; }  // last branching point
  double deadband() const noexcept { return deadband_; }

 private:
  double deadband_;
  double extremum_ = 0.0;
  double turning_point_ = 0.0;
  int direction_ = 0;
};

}  // namespace hystloop
