#include "ident/online_mem_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fmt/format.h>

#include "core/errors.hpp"
#include "ident/branches.hpp"

namespace hystloop {

std::string_view to_string(PoisonKind kind) noexcept {
  switch (kind) {
    case PoisonKind::none: return "none";
    case PoisonKind::non_finite: return "non-finite sample";
    case PoisonKind::dropout: return "sensor dropout (y stuck while u moves)";
  }
  return "unknown";
}

void OnlineMemOptions::validate() const {
  if (window_samples < 16) throw ParameterError("window_samples", "must be >= 16");
  if (capacity_samples < window_samples) throw ParameterError("capacity_samples", "must be >= window_samples");
  if (holdout_branches < 1) throw ParameterError("holdout_branches", "must be >= 1");
  require_in_range("min_relative_improvement", min_relative_improvement, 0.0, 1.0);
  require_positive("max_residual_rms_m", max_residual_rms_m);
  require_positive("max_relative_residual", max_relative_residual);
  if (stuck_samples < 2) throw ParameterError("stuck_samples", "must be >= 2");
  fit.validate();
}

OnlineMemEstimator::OnlineMemEstimator(const OnlineMemOptions& options, const MemParams& initial)
    : options_(options), params_(initial) {
  options_.validate();
  params_.validate();
  u_.assign(options_.capacity_samples, 0.0);
  y_.assign(options_.capacity_samples, 0.0);
  scratch_ = make_window();
}

FeedResult OnlineMemEstimator::feed(double u, double y) noexcept {
  const std::size_t i = static_cast<std::size_t>(seq_ % options_.capacity_samples);
  u_[i] = u;
  y_[i] = y;
  FeedResult result = FeedResult::stored;
  if (!std::isfinite(u) || !std::isfinite(y)) {
    ++non_finite_;
    poison_ = PoisonKind::non_finite;
    poison_seq_ = seq_;
    stuck_run_ = 0;
    result = FeedResult::non_finite;
  } else if (seq_ > 0 && y == last_y_ && u != last_u_) {
    if (++stuck_run_ >= options_.stuck_samples) {
      if (stuck_run_ == options_.stuck_samples) ++dropouts_;
      poison_ = PoisonKind::dropout;
      poison_seq_ = seq_;
      result = FeedResult::dropout;
    }
  } else {
    stuck_run_ = 0;
  }
  last_u_ = u;
  last_y_ = y;
  ++seq_;
  return result;
}

MemWindow OnlineMemEstimator::make_window() const {
  MemWindow w;
  w.u.reserve(options_.window_samples);
  w.y.reserve(options_.window_samples);
  return w;
}

void OnlineMemEstimator::snapshot(MemWindow& out) const {
  const std::size_t cap = options_.capacity_samples;
  const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(seq_, options_.window_samples));
  out.u.resize(n);  // no allocation: capacity reserved by make_window()
  out.y.resize(n);
  out.first_seq = seq_ - n;
  const std::size_t start = static_cast<std::size_t>(out.first_seq % cap);
  const std::size_t first_part = std::min(n, cap - start);
  std::memcpy(out.u.data(), u_.data() + start, first_part * sizeof(double));
  std::memcpy(out.y.data(), y_.data() + start, first_part * sizeof(double));
  std::memcpy(out.u.data() + first_part, u_.data(), (n - first_part) * sizeof(double));
  std::memcpy(out.y.data() + first_part, y_.data(), (n - first_part) * sizeof(double));
  const bool hit = poison_ != PoisonKind::none && n > 0 && poison_seq_ >= out.first_seq;
  out.poison = hit ? poison_ : PoisonKind::none;
  out.poison_seq = hit ? poison_seq_ : 0;
}

namespace {
// A held-out branch spans at least this fraction of the window's input range [-].
constexpr double kHeldOutMinSpan = 0.1;
}  // namespace

MemRefitOutcome OnlineMemEstimator::evaluate(const MemWindow& w, const MemParams& in_use, std::uint64_t version,
                                             const OnlineMemOptions& o) {
  MemRefitOutcome out;
  out.judged_against_version = version;
  auto refuse = [&](FitStatus s, std::string why) {
    out.status = s;
    out.reason = std::move(why);
    return out;
  };
  if (w.poison != PoisonKind::none) {
    return refuse(FitStatus::poisoned_window, fmt::format("window from sample {} holds a {} at sample {}", w.first_seq,
                                                          to_string(w.poison), w.poison_seq));
  }
  if (w.u.size() != w.y.size() || w.u.empty()) return refuse(FitStatus::size_mismatch, "empty window");
  const std::vector<BranchSegment> branches = split_branches(w.u, o.fit.reversal_dead_band_V);
  // Complete branches end at the next reversal: all but the last one. The held-out ones end at
  // the last complete branch that spans a real part of the window's input: a servo's jitter at
  // a turning point makes branches of a sample or two, and the offset-free RMS over such a
  // branch is about 0 for any set, which would judge every candidate "no better". Branches
  // after it are neither fitted nor held out.
  std::size_t complete = branches.empty() ? 0 : branches.size() - 1;
  if (complete > 0) {
    const auto [ulo, uhi] = std::minmax_element(w.u.begin(), w.u.end());
    const double significant_V = kHeldOutMinSpan * (*uhi - *ulo);
    while (complete > 0) {
      const BranchSegment& b = branches[complete - 1];
      if (b.size() > 1 && std::abs(w.u[b.end - 1] - b.origin_u) >= significant_V) break;
      --complete;
    }
  }
  if (complete < o.holdout_branches + o.fit.min_branches) {
    const auto [lo, hi] = std::minmax_element(w.u.begin(), w.u.end());
    if (*hi - *lo < std::max(o.fit.min_input_range_V, 1e-300)) {
      return refuse(FitStatus::constant_input, fmt::format("u spans {:g} V in the window: constant input", *hi - *lo));
    }
    return refuse(FitStatus::too_few_branches,
                  fmt::format("{} complete branches in the window; need {} to fit + {} held out", complete,
                              o.fit.min_branches, o.holdout_branches));
  }
  const std::span<const BranchSegment> held(branches.data() + complete - o.holdout_branches, o.holdout_branches);
  const std::size_t train_end = held.front().begin + 1;  // up to and including the held-out reversal
  out.fit = fit_mem(std::span(w.u).first(train_end), std::span(w.y).first(train_end), o.fit);
  out.candidate = out.fit.params;
  if (!out.fit.ok()) return refuse(out.fit.status, "fit: " + out.fit.reason);
  const auto [ylo, yhi] = std::minmax_element(w.y.begin(), w.y.end());
  const double bound = std::min(o.max_residual_rms_m, o.max_relative_residual * 0.5 * (*yhi - *ylo));
  if (!(out.fit.residual_rms_m <= bound)) {
    return refuse(FitStatus::out_of_range,
                  fmt::format("fit residual {:g} m exceeds the bound {:g} m", out.fit.residual_rms_m, bound));
  }
  out.holdout_rms_candidate_m = mem_branch_rms(w.u, w.y, held, out.candidate);
  out.holdout_rms_in_use_m = mem_branch_rms(w.u, w.y, held, in_use);
  if (!(out.holdout_rms_candidate_m < (1.0 - o.min_relative_improvement) * out.holdout_rms_in_use_m)) {
    return refuse(
        FitStatus::no_improvement,
        fmt::format("held-out branch RMS {:g} m vs {:g} m in use: not {:g} % better", out.holdout_rms_candidate_m,
                    out.holdout_rms_in_use_m, o.min_relative_improvement * 100.0));
  }
  out.status = FitStatus::ok;
  out.accepted = true;
  out.reason =
      fmt::format("held-out branch RMS {:g} m vs {:g} m in use", out.holdout_rms_candidate_m, out.holdout_rms_in_use_m);
  return out;
}

bool OnlineMemEstimator::adopt(const MemRefitOutcome& outcome) {
  if (!outcome.accepted || outcome.judged_against_version != version_) {
    ++rejected_;
    return false;
  }
  params_ = outcome.candidate;
  ++version_;
  ++accepted_;
  return true;
}

MemRefitOutcome OnlineMemEstimator::refit() {
  snapshot(scratch_);
  MemRefitOutcome out = evaluate(scratch_, params_, version_, options_);
  adopt(out);
  return out;
}

}  // namespace hystloop
