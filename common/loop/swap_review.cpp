#include "loop/swap_review.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"

namespace hystloop {

void SwapReviewConfig::validate() const {
  if (worse_ratio != 0.0) require_in_range("compensator.swap_worse_ratio", worse_ratio, 1.05, 100.0);
  require_in_range("compensator.swap_min_excess_m", min_excess_m, 0.0, 1e-6);
}

SwapReviewSpan swap_review_span(double period_s, double dt_s, std::int64_t horizon_ticks,
                                std::int64_t reanchor_ramp_ticks) noexcept {
  SwapReviewSpan s;
  if (!(period_s > 0.0) || !(dt_s > 0.0) || period_s > SwapReview::kMaxWindow_s) return s;
  // At least two periods and 0.1 s on each side (an RMS over ~1,000 ticks of 1 nm noise is known to
  // ~2 %), no more than kMaxWindow_s.
  double periods = std::max(2.0, std::ceil(0.1 / period_s));
  if (periods * period_s > SwapReview::kMaxWindow_s) periods = std::floor(SwapReview::kMaxWindow_s / period_s);
  // The swap settles when the re-anchoring's period has been measured (a period, then the plan's
  // lead for its samples to arrive) and ramped in (its ramp, and 20 ms for the servo to hand over).
  const double settle_s = period_s + static_cast<double>(horizon_ticks + reanchor_ramp_ticks) * dt_s + 0.02;
  const double settle_periods = std::ceil(settle_s / period_s);
  s.window_ticks = std::llround(periods * period_s / dt_s);
  s.settle_ticks = std::llround(settle_periods * period_s / dt_s);
  return s;
}

SwapReview::SwapReview(const SwapReviewConfig& config, std::int64_t max_window_ticks, std::int64_t plan_ahead_ticks)
    : config_(config),
      planned_(static_cast<std::size_t>(std::max<std::int64_t>(plan_ahead_ticks, 0) + 2)),
      errors_(static_cast<std::size_t>(std::max<std::int64_t>(max_window_ticks, 1))) {}

void SwapReview::planned(std::int64_t k, double y_ref_m, bool comparable) noexcept {
  if (first_planned_ < 0) first_planned_ = k;
  last_planned_ = std::max(last_planned_, k);
  planned_[static_cast<std::size_t>(k % static_cast<std::int64_t>(planned_.size()))] = {k, y_ref_m};
  if (!comparable) not_comparable(k);
}

void SwapReview::not_comparable(std::int64_t k) noexcept {
  if (first_planned_ < 0) first_planned_ = k;
  last_incomparable_ = std::max(last_incomparable_, k);
  if (reviewing() && k < after_end()) end_review();
}

bool SwapReview::swapped(std::int64_t k, SwapReviewSpan span, bool judge) noexcept {
  end_review();  // a review still under way is overtaken: its window after is no longer the set's
  const std::int64_t w = span.window_ticks;
  const bool judged = judge && config_.worse_ratio > 0.0 && w > 0 && w <= static_cast<std::int64_t>(errors_.size()) &&
                      first_planned_ >= 0 && k - w >= first_planned_ && k - w > last_incomparable_;
  // No window before a later swap spans this one's settling (nor this tick, when nothing settles).
  last_incomparable_ = std::max(last_incomparable_, k + std::max<std::int64_t>(span.settle_ticks - 1, 0));
  if (!judged) return false;
  swap_tick_ = k;
  span_ = span;
  before_done_ = false;
  after_sum_ = 0.0;
  after_count_ = 0;
  return true;
}

SwapReview::Verdict SwapReview::observe(std::int64_t seq, double y_m) noexcept {
  const Planned& p = planned_[static_cast<std::size_t>(seq % static_cast<std::int64_t>(planned_.size()))];
  const bool known = p.tick == seq && std::isfinite(p.y_ref_m) && std::isfinite(y_m);
  const double e2 = known ? (y_m - p.y_ref_m) * (y_m - p.y_ref_m) : 0.0;
  errors_[static_cast<std::size_t>(seq % static_cast<std::int64_t>(errors_.size()))] = {known ? seq : -1, e2};
  if (!reviewing()) return Verdict::none;
  const std::int64_t w = span_.window_ticks;
  // Nine in ten ticks of a window measured, or it says nothing.
  const auto enough = [w](std::int64_t n) { return 10 * n >= 9 * w; };
  if (!before_done_ && seq >= swap_tick_ - 1) {
    double sum = 0.0;
    std::int64_t n = 0;
    for (std::int64_t t = swap_tick_ - w; t < swap_tick_; ++t) {
      const Error& e = errors_[static_cast<std::size_t>(t % static_cast<std::int64_t>(errors_.size()))];
      if (e.tick == t) {
        sum += e.e2;
        ++n;
      }
    }
    if (!enough(n)) {
      end_review();
      return Verdict::none;
    }
    before_rms_m_ = std::sqrt(sum / static_cast<double>(n));
    before_done_ = true;
  }
  if (seq >= after_begin() && seq < after_end() && known) {
    after_sum_ += e2;
    ++after_count_;
  }
  if (seq < after_end() - 1) return Verdict::none;
  end_review();
  if (!before_done_ || !enough(after_count_)) return Verdict::none;
  after_rms_m_ = std::sqrt(after_sum_ / static_cast<double>(after_count_));
  const bool worse =
      after_rms_m_ > config_.worse_ratio * before_rms_m_ && after_rms_m_ - before_rms_m_ > config_.min_excess_m;
  return worse ? Verdict::worse : Verdict::kept;
}

}  // namespace hystloop
