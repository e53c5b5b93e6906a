#include "loop/parameter_exchange.hpp"

#include <algorithm>
#include <cmath>

namespace hystloop {
namespace {

// The re-anchoring window spans a whole period of the lines learning takes (learning.max_period_s,
// 0.1 s by default: 1,000 ticks, 32 kB), and a tick more, so that the period's second reversal
// falls inside it.
std::int64_t reanchor_max_ticks(const CompensatorConfig& config) {
  const double ticks = std::ceil(config.learning.max_period_s / config.dt_s) + 1.0;
  return static_cast<std::int64_t>(std::clamp(ticks, 1.0, 100000.0));
}

}  // namespace

ParameterExchange::ParameterExchange(const CompensatorConfig& config)
    : anchor_(config.reanchor_ticks, reanchor_max_ticks(config), config.reanchor_ramp_ticks,
              config.slew_fraction * config.slew_V_per_s * config.dt_s, config.reanchor_u_rate_V_per_s * config.dt_s) {}

void ParameterExchange::offer(const ModelParamSet& params, bool switch_model, std::int32_t version,
                              bool take_back) noexcept {
  pending_ = Pending{params, switch_model, take_back};
  pending_version_ = version;
}

bool ParameterExchange::switches_model(FeedforwardMode mode) const noexcept {
  return pending_->switch_model && mode != FeedforwardMode::kOff && mode_of(pending_->params.kind) != mode;
}

bool ParameterExchange::held_by_learning(FeedforwardMode mode, const LearnerFigures& f,
                                         const LearningConfig& config) const noexcept {
  if (!pending_) return false;
  const std::int64_t after = config.hold_params_after;
  if (after <= 0 || !f.active || f.tables_this_line < static_cast<std::uint64_t>(after)) return false;
  // A table near its bound is no converged line: a model far off, which the new set may repair.
  if (!(f.correction_rms_m < 0.5 * config.max_correction_m)) return false;
  // A set for a model the line does not use changes nothing it learned: it goes in as always.
  return switches_model(mode) || mode_of(pending_->params.kind) == mode;
}

ParameterExchange::Pending ParameterExchange::take() noexcept {
  Pending p = *pending_;
  pending_.reset();
  version_ = pending_version_;
  return p;
}

void ParameterExchange::carry_over(const ParameterExchange& from) noexcept {
  pending_ = from.pending_;
  pending_version_ = from.pending_version_;
  version_ = from.version_;
}

}  // namespace hystloop
