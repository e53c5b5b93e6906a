#include "loop/periodic_learner.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "core/errors.hpp"

namespace hystloop {
namespace {

constexpr std::int64_t kNoTick = std::numeric_limits<std::int64_t>::min();

// The -6 dB frequency of the triangle of half-width m: where an m-tick mean's gain
// sin(m x) / (m sin x), x = pi f dt, falls to 1/sqrt(2). It decreases monotonically on
// (0, pi/m), so bisection finds it.
double triangle_cutoff_hz(std::int64_t m, double dt_s) {
  const double md = static_cast<double>(m);
  double lo = 0.0, hi = std::numbers::pi / md;
  for (int it = 0; it < 80; ++it) {
    const double x = 0.5 * (lo + hi);
    if (std::sin(md * x) / (md * std::sin(x)) > std::numbers::sqrt2 / 2.0) {
      lo = x;
    } else {
      hi = x;
    }
  }
  return 0.5 * (lo + hi) / (std::numbers::pi * dt_s);
}

std::int64_t floor_mod(std::int64_t a, std::int64_t n) noexcept {
  const std::int64_t r = a % n;
  return r < 0 ? r + n : r;
}

}  // namespace

void LearningConfig::validate(double dt_s) const {
  require_positive("compensator.dt_s", dt_s);
  require_positive("learning.gain", gain);
  require_in_range("learning.gain", gain, 0.0, 1.0);
  require_positive("learning.max_correction_m", max_correction_m);
  // 100 um is beyond any piezo nanopositioner's range: a larger bound is a unit mistake.
  require_in_range("learning.max_correction_m", max_correction_m, 0.0, 1e-4);
  // Ten seconds at 10 kHz is 100 000 ticks per table (four tables): the memory stays small.
  require_in_range("learning.max_period_s", max_period_s, 2.0 * dt_s, 10.0);
  // Above fs/4 no window of two or more taps is -6 dB that high: there would be no filter, and
  // without one a plant delay of a tick makes the learning diverge near Nyquist.
  require_in_range("learning.cutoff_hz", cutoff_hz, 1.0 / max_period_s, 0.25 / dt_s);
  require_in_range("learning.fade_s", fade_s, dt_s, 10.0);
  require_in_range("learning.blend_s", blend_s, 0.0, 1.0);
  require_in_range("learning.ramp_periods", ramp_periods, 0.0, 100.0);
  if (hold_params_after < 0) throw ParameterError("learning.hold_params_after", "must be >= 0 (0: never hold)");
  if (monitor_ratio != 0.0) require_in_range("learning.monitor_ratio", monitor_ratio, 1.0, 100.0);
}

PeriodicLearner::PeriodicLearner(const LearningConfig& config, double dt_s, std::int64_t max_lag_ticks)
    : dt_s_(dt_s),
      gain_(config.gain),
      applied_weight_(config.lag_compensated ? config.gain : 1.0),
      max_correction_m_(config.max_correction_m),
      lag_compensated_(config.lag_compensated),
      enabled_(config.enabled),
      ramp_periods_(config.ramp_periods),
      monitor_ratio_(config.monitor_ratio) {
  config.validate(dt_s);
  require_in_range("learning.max_lag_ticks", static_cast<double>(max_lag_ticks), 0.0, 1e6);
  max_period_ = static_cast<std::int64_t>(std::floor(config.max_period_s / dt_s + 1e-9));
  fade_ticks_ = std::max<std::int64_t>(1, std::llround(config.fade_s / dt_s));
  blend_ticks_ = std::llround(config.blend_s / dt_s);
  // The longest window whose -6 dB frequency is still at or above the cutoff: an M-tick mean's
  // -3 dB is near 0.443 / (M dt); start there and correct for the discrete response.
  std::int64_t m = std::max<std::int64_t>(2, static_cast<std::int64_t>(0.443 / (config.cutoff_hz * dt_s)));
  m = std::min(m, max_period_);
  while (m > 2 && triangle_cutoff_hz(m, dt_s) < config.cutoff_hz) --m;
  while (m + 1 <= max_period_ && triangle_cutoff_hz(m + 1, dt_s) >= config.cutoff_hz) ++m;
  window_ = m;
  filter_cutoff_hz_ = triangle_cutoff_hz(m, dt_s);

  // A sample's slot must still hold its tick when the sample arrives max_lag_ticks later.
  const auto ring = static_cast<std::size_t>(max_lag_ticks + 1);
  ring_k_.assign(ring, kNoTick);
  ring_r_.assign(ring, 0.0);
  ring_c_.assign(ring, 0.0);
  ring_held_.assign(ring, 0);
  for (auto* v : {&table_, &next_, &prev_, &acc_, &tmp_, &applied_, &good_}) {
    v->assign(static_cast<std::size_t>(max_period_), 0.0);
  }
}

double PeriodicLearner::filter_null_hz() const noexcept { return 1.0 / (static_cast<double>(window_) * dt_s_); }

double PeriodicLearner::filter_norm_sq() const noexcept {
  const double m = static_cast<double>(window_);
  return (2.0 * m * m + 1.0) / (3.0 * m * m * m);
}

std::int64_t PeriodicLearner::phase(std::int64_t k) const noexcept { return floor_mod(k - table_k0_, table_n_); }

std::size_t PeriodicLearner::slot(std::int64_t k) const noexcept {
  return static_cast<std::size_t>(floor_mod(k, static_cast<std::int64_t>(ring_k_.size())));
}

void PeriodicLearner::restart(std::int64_t k0, std::int64_t period_ticks) noexcept {
  stopped_by_monitor_ = false;
  has_target_ = period_ticks >= 2 && period_ticks <= max_period_;
  k0_ = k0;
  n_ = has_target_ ? period_ticks : 0;
  begin_again();
}

void PeriodicLearner::stop() noexcept {
  stopped_by_monitor_ = false;
  has_target_ = false;
  n_ = 0;
  begin_again();
}

void PeriodicLearner::set_enabled(bool on) noexcept {
  if (on == enabled_) return;
  enabled_ = on;
  stopped_by_monitor_ = false;
  begin_again();
}

void PeriodicLearner::reset() noexcept {
  stopped_by_monitor_ = false;
  begin_again();
}

void PeriodicLearner::begin_again() noexcept {
  // Whatever was being observed or waiting belongs to what is being forgotten.
  pending_ = false;
  cur_open_ = false;
  figures_.period_ticks = n_;
  if ((mode_ == Mode::kLearning || mode_ == Mode::kHolding) && have_table_) {
    // A table in use is faded out, never dropped: dropping it would step the reference.
    // From what was applied last: a learning line under its ramp, a held table as it is.
    fade_from_ = mode_ == Mode::kLearning && last_planned_ != kNoTick ? ramp(last_planned_) : 1.0;
    mode_ = Mode::kFading;
    scale_ = 1.0;
    fade_left_ = fade_ticks_;
  } else if (mode_ != Mode::kFading) {
    start_learning(last_planned_ == kNoTick ? kNoTick : last_planned_ + 1);
  }
  // A fade under way goes on from where it is (no step) and starts the learning when it ends.
  figures_.active = mode_ == Mode::kLearning;
  figures_.fading = mode_ == Mode::kFading;
  figures_.holding = false;
}

void PeriodicLearner::start_learning(std::int64_t from_k) noexcept {
  have_table_ = false;
  have_prev_ = false;
  prev_scale_ = 1.0;
  blend_n_ = 0;
  ramp_ticks_ = 0;
  pending_ = false;
  cur_open_ = false;
  scale_ = 1.0;
  fade_from_ = 1.0;
  table_rms_m_ = 0.0;
  figures_.correction_rms_m = 0.0;
  figures_.tables_this_line = 0;
  baseline_rms_m_ = 0.0;
  baseline_sum_sq_ = 0.0;
  baseline_periods_ = 0;
  baseline_closed_ = false;
  above_once_ = false;
  compare_from_ = kNoTick;
  best_rms_m_ = 0.0;
  have_good_ = false;
  figures_.baseline_rms_m = 0.0;
  figures_.best_rms_m = 0.0;
  figures_.diverged = stopped_by_monitor_;
  if (!enabled_ || !has_target_ || stopped_by_monitor_) {
    mode_ = Mode::kIdle;
  } else {
    mode_ = Mode::kLearning;
    table_k0_ = k0_;
    table_n_ = n_;
    table_m_ = std::min(window_, n_);
    // The first period that starts at or after from_k: its every tick is planned by this learning.
    learn_start_ = k0_;
    if (from_k != kNoTick && from_k > k0_) learn_start_ = k0_ + (from_k - k0_ + n_ - 1) / n_ * n_;
    expect_start_ = learn_start_;
    last_observed_ = kNoTick;
  }
  figures_.active = mode_ == Mode::kLearning;
  figures_.fading = false;
}

double PeriodicLearner::correction(std::int64_t k, double r_k_m) noexcept {
  last_planned_ = k;
  if (mode_ == Mode::kFading) {
    --fade_left_;
    scale_ = static_cast<double>(fade_left_) / static_cast<double>(fade_ticks_);
    if (fade_left_ <= 0) start_learning(k);
  }
  double c = 0.0;
  if (mode_ == Mode::kLearning) {
    if (k >= table_k0_) {
      const std::int64_t i = phase(k);
      if (pending_ && i == 0) {
        // Only at a boundary: the table in use never changes inside a period except by the
        // blend from the one before (rotated out, no copy).
        std::swap(prev_, table_);
        std::swap(table_, next_);
        have_prev_ = have_table_;
        prev_scale_ = 1.0;
        have_table_ = true;
        adopted_k_ = k;
        blend_n_ = std::min(blend_ticks_, table_n_);
        pending_ = false;
        ++figures_.tables_adopted;
        if (++figures_.tables_this_line == 1) {
          ramp_k0_ = k;
          ramp_ticks_ = std::llround(ramp_periods_ * static_cast<double>(table_n_));
        }
        table_rms_m_ = pending_rms_m_;
        figures_.correction_rms_m = table_rms_m_;
      }
      if (have_table_) c = ramp(k) * in_use(k, i);
    }
  } else if (mode_ == Mode::kFading) {
    c = fade_from_ * scale_ * in_use(k, phase(k));
    figures_.correction_rms_m = fade_from_ * scale_ * table_rms_m_;
  } else if (mode_ == Mode::kHolding && k >= table_k0_) {
    c = in_use(k, phase(k));
  }
  const std::size_t s = slot(k);
  ring_k_[s] = k;
  ring_r_[s] = r_k_m;
  ring_c_[s] = c;
  ring_held_[s] = 0;
  return c;
}

double PeriodicLearner::in_use(std::int64_t k, std::int64_t i) const noexcept {
  const double now = table_[static_cast<std::size_t>(i)];
  const std::int64_t into = k - adopted_k_;
  if (into < 0 || into + 1 >= blend_n_) return now;
  const double before = have_prev_ ? prev_scale_ * prev_[static_cast<std::size_t>(i)] : 0.0;
  return before + (now - before) * static_cast<double>(into + 1) / static_cast<double>(blend_n_);
}

double PeriodicLearner::ramp(std::int64_t k) const noexcept {
  if (ramp_ticks_ <= 0) return 1.0;
  const std::int64_t into = k - ramp_k0_ + 1;
  if (into >= ramp_ticks_) return 1.0;
  return into <= 0 ? 0.0 : static_cast<double>(into) / static_cast<double>(ramp_ticks_);
}

void PeriodicLearner::hold(std::int64_t k) noexcept {
  const std::size_t s = slot(k);
  if (ring_k_[s] != k || ring_held_[s] != 0) return;
  ring_held_[s] = 1;
  ++figures_.ticks_held;
}

void PeriodicLearner::account_skipped(std::uint64_t n) noexcept {
  figures_.periods_completed += n;
  figures_.periods_skipped += n;
}

void PeriodicLearner::observe(std::int64_t k, double y_m) noexcept {
  if (mode_ != Mode::kLearning || k < learn_start_ || (last_observed_ != kNoTick && k <= last_observed_)) return;
  last_observed_ = k;
  const std::int64_t start = k - phase(k);
  if (!cur_open_ || start != cur_start_) {
    if (cur_open_) {
      // The period before ended without its last tick.
      account_skipped(1);
      expect_start_ = cur_start_ + table_n_;
    }
    // Periods of which not a single sample arrived.
    account_skipped(static_cast<std::uint64_t>((start - expect_start_) / table_n_));
    cur_open_ = true;
    cur_start_ = start;
    cur_ok_ = k == start;
    cur_sum_sq_ = 0.0;
    cur_max_ = 0.0;
    cur_under_table_ = false;
  } else if (k != cur_next_) {
    cur_ok_ = false;
  }
  cur_next_ = k + 1;

  const std::size_t s = slot(k);
  const double e = ring_r_[s] - y_m;
  if (ring_k_[s] == k && std::isfinite(e) && std::isfinite(ring_c_[s])) {
    // The part of the update that is this period's own: c_applied + gain*e, or its gain-weighted
    // share gain*(c_applied + e) when lag-compensated (learn_from_period adds the rest).
    acc_[static_cast<std::size_t>(k - start)] = applied_weight_ * ring_c_[s] + (ring_held_[s] != 0 ? 0.0 : gain_ * e);
    cur_sum_sq_ += e * e;
    cur_max_ = std::max(cur_max_, std::abs(e));
    applied_[static_cast<std::size_t>(k - start)] = ring_c_[s];
    cur_under_table_ = cur_under_table_ || ring_c_[s] != 0.0;
  } else {
    // No sample, or its slot was planned over (later than max_lag_ticks): the period has a hole.
    cur_ok_ = false;
  }

  if (k == start + table_n_ - 1) {
    cur_open_ = false;
    expect_start_ = start + table_n_;
    if (cur_ok_) {
      ++figures_.periods_completed;
      ++figures_.periods_learned;
      figures_.last_error_rms_m = std::sqrt(cur_sum_sq_ / static_cast<double>(table_n_));
      figures_.last_error_max_m = cur_max_;
      if (monitor(figures_.last_error_rms_m)) learn_from_period();
    } else {
      account_skipped(1);
    }
  }
}

void PeriodicLearner::params_swapped(std::int64_t k) noexcept {
  if (mode_ != Mode::kLearning) return;
  // The swap steps the error the tables had learned; the step is first learned from periods
  // observed a lag later and then goes by (1 - gain) a period: the periods planned up to the
  // lag and five more periods after the swap (3 % of the step left at the default gain) are not
  // compared.
  const auto lag = static_cast<std::int64_t>(ring_k_.size()) - 1;
  compare_from_ = std::max(compare_from_, k + lag + 5 * table_n_);
}

bool PeriodicLearner::monitor(double e_rms_m) noexcept {
  if (monitor_ratio_ == 0.0) return true;
  if (!cur_under_table_) {
    // The line's own error, nothing learned applied: pooled into the baseline until a period
    // under a table has been observed (the plan adopts the first table a lag before that).
    if (!baseline_closed_) {
      baseline_sum_sq_ += e_rms_m * e_rms_m;
      ++baseline_periods_;
      baseline_rms_m_ = figures_.baseline_rms_m = std::sqrt(baseline_sum_sq_ / static_cast<double>(baseline_periods_));
    }
    return true;
  }
  baseline_closed_ = true;
  if (baseline_rms_m_ == 0.0) return true;  // a fade from the line before: nothing to compare with
  if (compare_from_ != kNoTick && cur_start_ < compare_from_) return true;
  if (e_rms_m < baseline_rms_m_ && (!have_good_ || e_rms_m < best_rms_m_)) {
    best_rms_m_ = figures_.best_rms_m = e_rms_m;
    std::swap(applied_, good_);  // the corrections of this period: the table to fall back to
    have_good_ = true;
  }
  // A period's RMS of noise alone scatters by about 1 / sqrt(2n) of itself: twice the pooled
  // baseline's and the period's scatter once is a margin one noisy period may pass, twice it one
  // that only a growing error does.
  const double margin = 2.0 / std::sqrt(static_cast<double>(table_n_));
  if (!(e_rms_m > (monitor_ratio_ + margin) * baseline_rms_m_)) {
    above_once_ = false;
    return true;
  }
  if (!above_once_ && !(e_rms_m > (monitor_ratio_ + 2.0 * margin) * baseline_rms_m_)) {
    above_once_ = true;  // the next period says whether it grows
    return true;
  }
  ++figures_.divergences;
  figures_.diverged = true;
  stopped_by_monitor_ = true;
  pending_ = false;
  cur_open_ = false;
  if (have_good_) {
    // Hold the best period's corrections, taking over from the table in use (as its ramp applies
    // it) along the blend.
    prev_scale_ = ramp(last_planned_ + 1);
    std::swap(prev_, table_);
    std::swap(table_, good_);
    have_prev_ = have_table_;
    have_table_ = true;
    adopted_k_ = last_planned_ + 1;
    blend_n_ = std::max<std::int64_t>(1, std::min(std::max(blend_ticks_, fade_ticks_), table_n_));
    double sum_sq = 0.0;
    for (std::size_t i = 0; i < static_cast<std::size_t>(table_n_); ++i) sum_sq += table_[i] * table_[i];
    table_rms_m_ = std::sqrt(sum_sq / static_cast<double>(table_n_));
    figures_.correction_rms_m = table_rms_m_;
    mode_ = Mode::kHolding;
    figures_.holding = true;
    figures_.active = false;
    figures_.fading = false;
  } else {
    begin_again();  // fades the table in use out; the learning stays off for this line
  }
  return false;
}

void PeriodicLearner::learn_from_period() noexcept {
  if (lag_compensated_ && (pending_ || have_table_)) {
    // The new table replaces the newest one (waiting for a boundary, else in use), not the one
    // applied when the error was measured: learning gain*ê on top of it, with ê = e - (c_newest -
    // c_applied) the error c_newest would give if T = 1, is (1 - gain) c_newest + gain (c_applied
    // + e). acc_ holds the second term; add the first (before the filter overwrites next_).
    const std::vector<double>& newest = pending_ ? next_ : table_;
    const double keep = 1.0 - gain_;
    for (std::size_t i = 0; i < static_cast<std::size_t>(table_n_); ++i) acc_[i] += keep * newest[i];
  }
  // Q = two running means over the circular period: tmp[i] = mean(acc[i-m+1 .. i]), then
  // next[i] = mean(tmp[i .. i+m-1]). The looking-back and looking-ahead halves cancel each other's
  // delay, so the result is the zero-phase triangle; 4 additions and 2 multiplications per phase.
  const std::int64_t n = table_n_, m = table_m_;
  const double inv_m = 1.0 / static_cast<double>(m);
  double sum = 0.0;
  for (std::int64_t j = 0; j < m; ++j) sum += acc_[static_cast<std::size_t>(floor_mod(-j, n))];
  tmp_[0] = sum * inv_m;
  for (std::int64_t i = 1, out = n - m + 1; i < n; ++i, ++out) {  // out = (i - m) mod n
    if (out >= n) out -= n;
    sum += acc_[static_cast<std::size_t>(i)] - acc_[static_cast<std::size_t>(out)];
    tmp_[static_cast<std::size_t>(i)] = sum * inv_m;
  }
  sum = 0.0;
  for (std::int64_t j = 0; j < m; ++j) sum += tmp_[static_cast<std::size_t>(j)];
  double sum_sq = 0.0;
  auto put = [&](std::int64_t i, double v) {
    const double c = std::clamp(v, -max_correction_m_, max_correction_m_);
    next_[static_cast<std::size_t>(i)] = c;
    sum_sq += c * c;
  };
  put(0, sum * inv_m);
  for (std::int64_t i = 1, in = m; i < n; ++i, ++in) {  // in = (i + m - 1) mod n
    if (in >= n) in -= n;
    sum += tmp_[static_cast<std::size_t>(in)] - tmp_[static_cast<std::size_t>(i - 1)];
    put(i, sum * inv_m);
  }
  pending_rms_m_ = std::sqrt(sum_sq / static_cast<double>(n));
  pending_ = true;
}

}  // namespace hystloop
