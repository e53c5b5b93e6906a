#include "sim/loop_simulation.hpp"

#include <cmath>
#include <limits>

#include "core/errors.hpp"

namespace hystloop {
namespace {

// The series plant is sampled at the loop's tick (the others take dt per step).
SimulatedStageConfig at_tick(SimulatedStageConfig stage, double dt_s) {
  stage.tick_s = dt_s;
  return stage;
}

}  // namespace

LoopSimulation::LoopSimulation(const LoopSimulationConfig& config)
    : config_(config),
      dt_s_(config.compensator.dt_s),
      bridge_(config.limits, config.servo, config.compensator.dt_s),
      stage_(at_tick(config.stage, config.compensator.dt_s)),
      compensator_(config.compensator),
      plan_(1000) {
  require_in_range("loop.block_ticks", config.block_ticks, 1, 1000);
}

void LoopSimulation::run(double seconds, const std::function<void(const LoopTick&)>& on_tick) {
  const auto n = static_cast<std::int64_t>(std::llround(seconds / dt_s_));
  if (keep_history_) history_.reserve(history_.size() + static_cast<std::size_t>(n));
  for (std::int64_t i = 0; i < n; ++i, ++k_) {
    const double t = static_cast<double>(k_) * dt_s_;
    const BridgeTick b = bridge_.tick(k_, y_last_m_);
    const double y = stage_.step(b.u_applied_V, t, dt_s_);
    y_last_m_ = y;

    LoopTick rec;
    rec.k = k_;
    rec.t_s = t;
    rec.u_V = b.u_applied_V;
    rec.y_m = y;
    rec.y_true_m = stage_.true_position_m();
    rec.y_ref_m = b.y_ref_m;
    rec.flags = b.flags | sample_flags::kSimulated;
    rec.params_version = b.params_version;

    compensator_.observe({k_, b.u_applied_V, y, b.u_ff_V, (b.flags & sample_flags::kSafeState) != 0});
    if ((k_ + 1) % config_.block_ticks == 0) {  // a sensor block is complete: the compensator answers it
      while (const std::size_t planned = compensator_.plan(plan_)) {
        for (std::size_t j = 0; j < planned; ++j) bridge_.submit(plan_[j]);
      }
      // As the bridge's auto_arm does: armed once commands flow, so that a first block longer
      // than the watchdog's time does not trip it before anything was planned.
      if (!armed_) {
        bridge_.arm(k_ + 1);
        armed_ = true;
      }
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
