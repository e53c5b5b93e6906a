#pragma once
// Whether a parameter set swapped in on a periodic line tracks that line worse than the set it
// replaced. A refit is judged by how it explains its window of (u, y), not by the tracking it will
// give; a window that held two references (the end of one line and the start of the next, or an
// identification sine and the line after it) fits a set that explains neither, and its held-out
// branch, taken from the newer part, can still pass. The tracking error on the line itself is the
// judge no fit can be: the measured RMS of y - y_ref over `window` ticks just before the swap
// against the same over `window` ticks after it has settled. A swap worse by more than worse_ratio
// and by more than min_excess_m is taken back (the planner swaps the set before it in again).
//
// Only ticks that are comparable are judged: a periodic trajectory past its approach and first
// period, no scan, no learned correction (the learning changes the error by itself; it has its own
// monitor), no experiment. A tick planned otherwise ends any review whose span it falls in, and no
// window before a later swap reaches back across it. The error is the measured one: the sensor's
// noise is in both windows alike, which the ratio and the excess are set above.
//
// Allocation-free after construction: the planned references and the measured errors are rings.
// Time is the tick (any clock is the caller's).

#include <algorithm>
#include <cstdint>
#include <vector>

namespace hystloop {

struct SwapReviewConfig {
  double worse_ratio = 1.5;      // take back when after > worse_ratio x before (0: never judged)
  double min_excess_m = 0.5e-9;  // ... and after - before > this [m]
  void validate() const;         // throws ParameterError naming the field
};

// How long a review of a line of period_s takes [ticks], for a plan running horizon_ticks ahead
// whose re-anchoring measures a period and ramps in over reanchor_ramp_ticks: no window when the
// line is too slow to judge within max_window_s.
struct SwapReviewSpan {
  std::int64_t window_ticks = 0;  // each side (0: the line is not judged)
  std::int64_t settle_ticks = 0;  // skipped after the swap
};
SwapReviewSpan swap_review_span(double period_s, double dt_s, std::int64_t horizon_ticks,
                                std::int64_t reanchor_ramp_ticks) noexcept;

class SwapReview {
 public:
  static constexpr double kMaxWindow_s = 1.0;
  enum class Verdict : std::uint8_t { none, kept, worse };

  // max_window_ticks: the longest window swap_review_span can return at this tick; plan_ahead_ticks:
  // how far the plan runs ahead of the samples.
  SwapReview(const SwapReviewConfig& config, std::int64_t max_window_ticks, std::int64_t plan_ahead_ticks);

  // Every tracking tick as it is planned, in order: its sensor reference and whether it is
  // comparable (see above). A tick that is not ends a review whose span holds it.
  void planned(std::int64_t k, double y_ref_m, bool comparable) noexcept;
  // Tick k is not comparable (an experiment's, a hold before the anchor): as planned(k, -, false).
  void not_comparable(std::int64_t k) noexcept;
  // A set swapped in at planned tick k. Starts a review when `judge`, the window before it is all
  // comparable and `span` judges this line; returns whether it did. Either way a review under way
  // ends, and no later window before a swap reaches back across this one's settling.
  bool swapped(std::int64_t k, SwapReviewSpan span, bool judge = true) noexcept;
  // A sample, in order. Returns the verdict when the window after the swap is complete.
  Verdict observe(std::int64_t seq, double y_m) noexcept;

  bool reviewing() const noexcept { return swap_tick_ >= 0; }
  // Ends a review under way without a verdict, and no later window reaches back before the next
  // tick planned (a mode changed by hand).
  void cancel() noexcept {
    end_review();
    if (last_planned_ >= 0) last_incomparable_ = std::max(last_incomparable_, last_planned_ + 1);
  }
  // Of the last verdict: the measured RMS error before and after the swap [m].
  double before_rms_m() const noexcept { return before_rms_m_; }
  double after_rms_m() const noexcept { return after_rms_m_; }
  const SwapReviewConfig& config() const noexcept { return config_; }

 private:
  struct Planned {
    std::int64_t tick = -1;
    double y_ref_m = 0.0;
  };
  struct Error {
    std::int64_t tick = -1;
    double e2 = 0.0;  // squared measured error [m^2]
  };
  void end_review() noexcept { swap_tick_ = -1; }
  std::int64_t after_begin() const noexcept { return swap_tick_ + span_.settle_ticks; }
  std::int64_t after_end() const noexcept { return after_begin() + span_.window_ticks; }

  SwapReviewConfig config_;
  std::vector<Planned> planned_;         // by tick, over the plan's lead
  std::vector<Error> errors_;            // by tick, over the longest window
  std::int64_t first_planned_ = -1;      // the first tick planned (-1: none yet)
  std::int64_t last_planned_ = -1;       // the last
  std::int64_t last_incomparable_ = -1;  // the last tick not comparable, or settling after a swap
  std::int64_t swap_tick_ = -1;          // the swap under review (-1: none)
  SwapReviewSpan span_{};
  bool before_done_ = false;
  double before_rms_m_ = 0.0;
  double after_sum_ = 0.0;
  std::int64_t after_count_ = 0;
  double after_rms_m_ = 0.0;
};

}  // namespace hystloop
