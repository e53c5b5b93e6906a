#include "loop/feedforward_anchor.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"

namespace hystloop {

FeedforwardAnchor::FeedforwardAnchor(std::int64_t measure_ticks, std::int64_t max_measure_ticks,
                                     std::int64_t min_ramp_ticks, double max_du_per_tick, double max_u_offset_per_tick)
    : measure_ticks_(measure_ticks),
      max_measure_ticks_(std::max(measure_ticks, max_measure_ticks)),
      min_ramp_ticks_(min_ramp_ticks),
      max_du_per_tick_(max_du_per_tick),
      max_u_offset_per_tick_(max_u_offset_per_tick) {
  require_in_range("compensator.reanchor_ticks", static_cast<double>(measure_ticks), 1.0, 1000.0);
  require_in_range("compensator.reanchor_ramp_ticks", static_cast<double>(min_ramp_ticks), 1.0, 100000.0);
  require_positive("compensator.slew_fraction", max_du_per_tick);
  require_positive("compensator.reanchor_u_rate_V_per_s", max_u_offset_per_tick);
  require_in_range("the re-anchoring window", static_cast<double>(max_measure_ticks_), 1.0, 1e6);
  for (auto* v : {&y_model_, &u_model_}) v->assign(static_cast<std::size_t>(max_measure_ticks_), 0.0);
}

double FeedforwardAnchor::Ramp::at(std::int64_t k) const noexcept {
  if (k >= start + ticks) return to;
  if (k <= start) return from;
  return from + (to - from) * static_cast<double>(k - start) / static_cast<double>(ticks);
}

double FeedforwardAnchor::y_offset(std::int64_t k) const noexcept { return y_.at(k); }
double FeedforwardAnchor::u_offset(std::int64_t k) const noexcept { return u_.at(k); }

void FeedforwardAnchor::reset(double y_offset, double u_offset) noexcept {
  y_ = Ramp{y_offset, y_offset, 0, 1};
  u_ = Ramp{u_offset, u_offset, 0, 1};
  measuring_ = false;
}

void FeedforwardAnchor::start_measuring(std::int64_t first_tick) noexcept {
  measuring_ = true;
  first_ = first_tick;
  have_planned_ = 0;
  all_ = first_ticks_ = Sums{};
  window_ = 0;
  reversals_ = 0;
}

void FeedforwardAnchor::planned(std::int64_t k, double y_model, double u_model, bool reversal) noexcept {
  if (!measuring_) return;
  const std::int64_t i = k - first_;
  if (i < 0 || (window_ > 0 && i >= window_)) return;
  if (i > 0 && reversal) {
    ++reversals_;
    // A whole period: the window ends before the second reversal after its first tick.
    if (reversals_ % 2 == 0 && i >= measure_ticks_) {
      window_ = i;
      return;
    }
  }
  const auto j = static_cast<std::size_t>(i);
  y_model_[j] = y_model;
  u_model_[j] = u_model;
  have_planned_ = i + 1;
  if (i == 0) u_first_ = u_model, y_first_ = y_model;
  if (reversals_ == 0) u_last_ = u_model, y_last_ = y_model;  // the secant along the first branch
  // No period inside the window (a slow or aperiodic reference): its first ticks, as near the
  // reversal as they are.
  if (i + 1 == max_measure_ticks_) window_ = reversals_ >= 2 ? i + 1 : measure_ticks_;
}

bool FeedforwardAnchor::observe(std::int64_t seq, double y_measured, double u_applied, std::int64_t ramp_start,
                                double fallback_slope) noexcept {
  if (!measuring_) return false;
  const std::int64_t i = seq - first_;
  if (i < 0) return false;
  if (i < have_planned_ && (window_ == 0 || i < window_)) {
    const auto j = static_cast<std::size_t>(i);
    const double dy = y_measured - y_model_[j], du = u_applied - u_model_[j];
    all_.add(dy, du);
    if (i < measure_ticks_) first_ticks_.add(dy, du);
  }
  // Complete at the window's last tick, or at the first sample after its end became known (a
  // slow reference's window is cut back to its first ticks once max_measure_ticks are planned,
  // when later ticks may have been observed already: their sums are kept apart). The mean over
  // the ticks observed: a tick lost on the way is left out.
  const Sums& s = window_ > measure_ticks_ ? all_ : first_ticks_;
  if (window_ == 0 || i + 1 < window_ || s.n == 0) return false;
  const double y_target = s.dy / static_cast<double>(s.n);
  const double u_target = s.du / static_cast<double>(s.n);
  measuring_ = false;
  if (!std::isfinite(y_target) || !std::isfinite(u_target)) return false;
  ramp_to(y_target, u_target, ramp_start, fallback_slope);
  return true;
}

void FeedforwardAnchor::ramp_to(double y_target, double u_target, std::int64_t ramp_start, double fallback) noexcept {
  const double y_now = y_offset(ramp_start), u_now = u_offset(ramp_start);
  double slope = std::abs(fallback);
  if (std::abs(u_last_ - u_first_) > 1.0) slope = std::abs((y_last_ - y_first_) / (u_last_ - u_first_));
  if (!(slope > 0.0) || !std::isfinite(slope)) slope = std::abs(fallback);
  auto ticks = [&](double du, double per_tick) {
    const double need = std::min(std::ceil(du / per_tick), 1e7);
    return std::max<std::int64_t>(min_ramp_ticks_, std::isfinite(need) ? static_cast<std::int64_t>(need) : 0);
  };
  y_ = Ramp{y_now, y_target, ramp_start,
            ticks(slope > 0.0 ? std::abs(y_target - y_now) / slope : 0.0, max_du_per_tick_)};
  u_ = Ramp{u_now, u_target, ramp_start, ticks(std::abs(u_target - u_now), max_u_offset_per_tick_)};
}

}  // namespace hystloop
