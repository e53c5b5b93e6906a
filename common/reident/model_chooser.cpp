#include "reident/model_chooser.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <utility>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "core/clock.hpp"
#include "core/errors.hpp"
#include "ident/online_mem_estimator.hpp"
#include "reident/reident_core.hpp"

namespace hystloop {

const char* ModelChooser::counter_name(std::size_t i) noexcept {
  static constexpr const char* kNames[kCounters] = {"model_selections",
                                                    "model_changes",
                                                    "model_refits",
                                                    "model_kept",
                                                    "model_failed",
                                                    "model_poisoned",
                                                    "model_refits_left_to_mem",
                                                    "model_implausible",
                                                    "model_held",
                                                    "model_unsettled"};
  return i < kCounters ? kNames[i] : "model_unknown";
}

ModelChooser::ModelChooser(const ModelChoiceOptions& options, const ModelParamSet& initial, MemWindow window,
                           bool start_thread)
    : options_(options),
      in_use_(initial),
      window_(std::move(window)),
      slot_([this] { evaluate_job(); }, options.enabled && start_thread) {
  options_.selector.validate();
  if (options_.regime_factor != 0.0) require_in_range("regime_factor", options_.regime_factor, 1.0, 1e6);
  in_use_.validate();
}

std::optional<double> ModelChooser::recent_median_then_add(double best_m) {
  std::optional<double> median;
  const std::size_t n = std::min(recent_count_, kRecentFits);
  if (n >= 2) {
    std::array<double, kRecentFits> sorted = recent_best_m_;
    std::sort(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(n));
    median = n % 2 == 1 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
  }
  if (std::isfinite(best_m)) recent_best_m_[recent_count_++ % kRecentFits] = best_m;
  return median;
}

void ModelChooser::evaluate_job() {
  const double t0_s = monotonic_s();
  try {
    result_ = job_poisoned_ ? ModelProposal{} : propose_model(window_.u, window_.y, job_in_use_, job_options_);
    if (job_poisoned_) result_.reason = "window poisoned (non-finite sample or dropout)";
  } catch (const std::exception& e) {
    result_ = ModelProposal{};
    result_.reason = e.what();
  }
  duration_s_ = monotonic_s() - t0_s;
  spdlog::debug("model selection: {} ({:.0f} ms)", result_.reason, duration_s_ * 1e3);
}

namespace {
// The set a pinned kind starts from when it is not in use: a valid set of that kind (the
// selector refits it on the window and proposes the refit when it beats this one).
ModelParamSet start_of(ModelKind kind, const MemParams& mem) {
  ModelParamSet s;
  s.kind = kind;
  s.mem = mem;
  if (kind == ModelKind::pi) s.pi = pi_params_from_mem(mem, 15, 250.0);
  if (kind == ModelKind::linear) s.linear = linear_params_from_mem(mem, 250.0);
  return s;
}
}  // namespace

ModelDecision ModelChooser::collect(ReidentCore& core) {
  ModelDecision d;
  const ModelProposal& p = result_;
  last_reason_ = p.reason;  // the I/O thread's copy (allocates only while it grows; 0.2 Hz)
  if (job_poisoned_) {
    ++counters_[poisoned];
    return d;
  }
  if (p.status != FitStatus::ok) {
    ++counters_[failed];
    return d;
  }
  ++counters_[selections];
  const std::optional<double> recent_m = recent_median_then_add(p.winner_holdout_rms_m);
  const bool pinned_elsewhere = options_.pinned && *options_.pinned != in_use_.kind;
  if (p.proposes() && core.estimator().restarted_since(fed_at_last_)) {
    // Fitted on the reference before the one now requested: a regime the line no longer has.
    ++counters_[unsettled];
    last_reason_ = "not published: fitted on the window before a new reference";
    return d;
  }
  if (!p.proposes() && !pinned_elsewhere) {
    ++counters_[kept];
    return d;
  }
  // Below a nanometre a window is explained to a nanopositioning sensor's noise: a ratio of such
  // residuals (noise-free test data fits to 1e-15 m) says nothing about the regime.
  constexpr double kRegimeFloor_m = 1e-9;
  const double proposed_m =
      p.kind == ProposalKind::model_change ? p.winner_holdout_rms_m : p.in_use_refit_holdout_rms_m;
  if (p.proposes() && options_.regime_factor > 0.0 && recent_m &&
      proposed_m > options_.regime_factor * std::max(*recent_m, kRegimeFloor_m)) {
    ++counters_[unsettled];
    last_reason_ = fmt::format(
        "not published: held-out RMS {:.3g} m, more than {:g} x the recent selections' {:.3g} m (a window across "
        "a change of regime)",
        proposed_m, options_.regime_factor, *recent_m);
    spdlog::info("model selection: {} {}", to_string(p.params.kind), last_reason_);
    return d;
  }
  // Pinned to a kind not in use: the user asked for it, so it is switched to whether or not it
  // wins; its refit when that beat the start set on the held-out branch, else the start set.
  const ModelParamSet& set = p.proposes() ? p.params : job_in_use_;
  const bool change = p.kind == ProposalKind::model_change || set.kind != in_use_.kind;
  if (!change && set.kind == ModelKind::mem) {
    ++counters_[left_to_mem];  // the MEM refit publishes MEM's parameters on HX_PARAMS
    return d;
  }
  // What the compensator would refuse as not this stage's (a units error: y 1000x) is not sent.
  try {
    require_plausible(set, core.options().plausibility);
  } catch (const ParameterError& e) {
    ++counters_[implausible];
    last_reason_ = std::string("not published: ") + e.what();
    spdlog::warn("model selection: {} {} refused: {}", to_string(set.kind),
                 p.kind == ProposalKind::model_change ? "change" : "refit", e.what());
    return d;
  }
  if (core.held()) {
    ++counters_[held];
    last_reason_ = "not published: the operator holds the set in use";
    return d;
  }
  // A proposal made against a set that changed meanwhile (HX_PARAMS from elsewhere) is still
  // judged on this window: the compensator swaps only at a reversal, so the newest wins anyway.
  d.kind = change ? ModelDecision::Kind::change : ModelDecision::Kind::refit;
  d.params = set;
  d.proposal = p;
  d.window_samples = window_.u.size();
  d.version = set.kind == ModelKind::mem ? core.adopt_own_mem(set.mem) : core.claim_diagnostic_version();
  ++counters_[change ? changes : refits];
  in_use_ = set;
  core.set_mem_refits(in_use_.kind == ModelKind::mem);
  return d;
}

ModelDecision ModelChooser::poll(ReidentCore& core, std::int64_t now_us) {
  if (!options_.enabled) return {};
  ModelDecision d;
  if (slot_.done()) {
    d = collect(core);
    slot_.release();
  }
  const std::uint64_t fed = core.estimator().samples_fed();
  const std::size_t window = core.options().estimator.window_samples;
  if (slot_.idle() && now_us >= next_us_ && core.estimator().samples_since_restart() >= window && fed != fed_at_last_) {
    core.estimator().snapshot(window_);  // allocation-free: window_ came from make_window()
    job_poisoned_ = window_.poison != PoisonKind::none;
    if (in_use_.kind == ModelKind::mem) in_use_.mem = core.in_use().params();  // MEM refits move it
    const bool pinned_elsewhere = options_.pinned && *options_.pinned != in_use_.kind;
    job_in_use_ = pinned_elsewhere ? start_of(*options_.pinned, core.in_use().params()) : in_use_;
    job_options_ = options_.selector;
    job_options_.pinned = options_.pinned.has_value();
    fed_at_last_ = fed;
    next_us_ = now_us + std::llround(options_.period_s * 1e6);
    slot_.submit();
  }
  return d;
}

}  // namespace hystloop
