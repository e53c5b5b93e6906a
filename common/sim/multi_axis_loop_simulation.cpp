#include "sim/multi_axis_loop_simulation.hpp"

#include <cmath>
#include <span>
#include <string>

#include "core/errors.hpp"

namespace hystloop {

namespace {

std::span<const ActuatorLimits> first(const std::array<ActuatorLimits, kScanAxes>& a, int n) {
  return {a.data(), static_cast<std::size_t>(n)};
}
std::span<const FeedbackGains> first(const std::array<FeedbackGains, kScanAxes>& a, int n) {
  return {a.data(), static_cast<std::size_t>(n)};
}

// The series plant is sampled at the loop's tick (the others take dt per step).
MultiAxisStageConfig at_tick(MultiAxisStageConfig stage, double dt_s) {
  for (SimulatedStageConfig& axis : stage.axis) axis.tick_s = dt_s;
  return stage;
}

double common_dt(const MultiAxisLoopConfig& c) {
  const double dt = c.compensator[0].dt_s;
  at_tick(c.stage, dt).validate();
  for (int i = 1; i < c.axes(); ++i) {
    if (c.compensator[static_cast<std::size_t>(i)].dt_s != dt) {
      throw ParameterError(std::string(axis_name(i)) + ".compensator.dt_s",
                           "must be x's (" + number_text(dt) + " s): the axes share one tick clock");
    }
  }
  require_in_range("loop.block_ticks", c.block_ticks, 1, 1000);
  return dt;
}

}  // namespace

MultiAxisLoopSimulation::MultiAxisLoopSimulation(const MultiAxisLoopConfig& config)
    : config_(config),
      dt_s_(common_dt(config)),
      bridge_(config.axes(), first(config.limits, config.axes()), first(config.servo, config.axes()), dt_s_),
      stage_(at_tick(config.stage, dt_s_)),
      plan_(1000) {
  compensators_.reserve(static_cast<std::size_t>(axes()));
  for (int i = 0; i < axes(); ++i) {
    const auto at = static_cast<std::size_t>(i);
    validate_within(std::string(axis_name(i)) + ".", [&] { config.compensator[at].validate(); });
    compensators_.emplace_back(config.compensator[at]);
  }
}

void MultiAxisLoopSimulation::take_path(const RasterSpec& raster, const AxisCoupling& decoupling, double blend_s) {
  take(raster, decoupling, blend_s);
}

void MultiAxisLoopSimulation::take_path(const LissajousSpec& lissajous, const AxisCoupling& decoupling,
                                        double blend_s) {
  take(lissajous, decoupling, blend_s);
}

template <class Path>
void MultiAxisLoopSimulation::take(const Path& path, const AxisCoupling& decoupling, double blend_s) {
  if (decoupling.n() != axes()) {
    throw ParameterError("decoupling",
                         "is for " + std::to_string(decoupling.n()) + " axes, the stage has " + std::to_string(axes()));
  }
  std::vector<ScanShare> shares;
  std::vector<Compensator*> laws;
  shares.reserve(static_cast<std::size_t>(axes()));
  for (int i = 0; i < axes(); ++i) {
    shares.emplace_back(path, i, AxisVector(decoupling.inverse_matrix().row(i).transpose()));
    laws.push_back(&compensators_[static_cast<std::size_t>(i)]);
  }
  take_scan_on_every_axis(laws, shares, blend_s);
}

void MultiAxisLoopSimulation::run(double seconds, const std::function<void(const MultiAxisTick&)>& on_tick) {
  const auto n = static_cast<std::int64_t>(std::llround(seconds / dt_s_));
  const auto axes_n = static_cast<std::size_t>(axes());
  AxisPositions u{}, y{};
  for (std::int64_t step = 0; step < n; ++step, ++k_) {
    const double t = static_cast<double>(k_) * dt_s_;
    bridge_.tick(k_, y_last_m_, ticks_);
    for (std::size_t i = 0; i < axes_n; ++i) u[i] = ticks_[i].u_applied_V;
    stage_.step(u, t, dt_s_, y);
    y_last_m_ = y;

    MultiAxisTick rec;
    rec.k = k_;
    rec.t_s = t;
    for (std::size_t i = 0; i < axes_n; ++i) {
      rec.u_V[i] = u[i];
      rec.y_m[i] = y[i];
      rec.y_true_m[i] = stage_.true_position_m(static_cast<int>(i));
      rec.y_ref_m[i] = ticks_[i].y_ref_m;
      rec.flags[i] = ticks_[i].flags | sample_flags::kSimulated;
      compensators_[i].observe({k_, u[i], y[i], ticks_[i].u_ff_V, (ticks_[i].flags & sample_flags::kSafeState) != 0});
    }
    if ((k_ + 1) % config_.block_ticks == 0) {
      for (std::size_t i = 0; i < axes_n; ++i) {
        while (const std::size_t planned = compensators_[i].plan(plan_)) {
          if (drop_[i]) continue;
          for (std::size_t j = 0; j < planned; ++j) bridge_.submit(static_cast<int>(i), plan_[j]);
        }
      }
      if (!armed_) {
        bridge_.arm(k_ + 1);
        armed_ = true;
      }
    }
    if (on_tick) on_tick(rec);
  }
}

}  // namespace hystloop
