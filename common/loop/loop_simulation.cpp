#include "loop/loop_simulation.hpp"

#include <cmath>
#include <limits>

namespace hystloop {

namespace {
constexpr std::size_t kRing = 64;
}

LoopSimulation::LoopSimulation(const LoopSimulationConfig& config)
    : config_(config),
      dt_s_(config.compensator.dt_s),
      bridge_(config.limits, config.compensator.dt_s),
      stage_(config.stage),
      compensator_(config.compensator),
      ref_by_tick_(kRing, std::numeric_limits<double>::quiet_NaN()) {
  bridge_.arm(0.0);
  // Prime the bridge: the commands for the first `lead` ticks hold the safe voltage.
  for (std::int64_t k = 0; k < config.compensator.lead_ticks; ++k) {
    bridge_.submit(k, config.limits.safe_u_V, 0, 0.0);
  }
}

void LoopSimulation::run(double seconds, const std::function<void(const LoopTick&)>& on_tick) {
  const auto n = static_cast<std::int64_t>(std::llround(seconds / dt_s_));
  if (keep_history_) history_.reserve(history_.size() + static_cast<std::size_t>(n));
  for (std::int64_t i = 0; i < n; ++i, ++k_) {
    const double t = static_cast<double>(k_) * dt_s_;
    const BridgeTick b = bridge_.tick(k_, t);
    const double y = stage_.step(b.u_applied_V, t, dt_s_);

    LoopTick rec;
    rec.k = k_;
    rec.t_s = t;
    rec.u_V = b.u_applied_V;
    rec.y_m = y;
    rec.y_true_m = stage_.true_position_m();
    rec.flags = b.flags | sample_flags::kSimulated;
    rec.params_version = b.params_version;
    double& slot = ref_by_tick_[static_cast<std::size_t>(k_) % kRing];
    rec.y_ref_m = slot;
    slot = std::numeric_limits<double>::quiet_NaN();

    if (const auto cmd = compensator_.update({k_, b.u_applied_V, y})) {
      bridge_.submit(cmd->seq, cmd->u_V, cmd->params_version, t);
      ref_by_tick_[static_cast<std::size_t>(cmd->seq) % kRing] = cmd->y_ref_m;
    }
    if (keep_history_) history_.push_back(rec);
    if (on_tick) on_tick(rec);
  }
}

TrackingStats LoopSimulation::tracking(double from_s, double to_s) const {
  TrackingStats s;
  double sum_meas = 0.0, sum_true = 0.0;
  for (const LoopTick& r : history_) {
    if (r.t_s < from_s || r.t_s >= to_s || !std::isfinite(r.y_ref_m)) continue;
    const double em = r.y_ref_m - r.y_m;
    const double et = r.y_ref_m - r.y_true_m;
    sum_meas += em * em;
    sum_true += et * et;
    s.max_abs_true_m = std::max(s.max_abs_true_m, std::abs(et));
    ++s.n;
  }
  if (s.n > 0) {
    s.rms_measured_m = std::sqrt(sum_meas / static_cast<double>(s.n));
    s.rms_true_m = std::sqrt(sum_true / static_cast<double>(s.n));
  }
  return s;
}

}  // namespace hystloop
