#include "ident/stage_removal.hpp"

#include <cmath>

namespace hystloop {

StageRemoval::StageRemoval(const StageModel& stage, double dt_s)
    : stage_(stage), dt_s_(dt_s), forward_(stage.is_second_order() ? stage.second_order : SecondOrderStageParams{}) {
  if (stage_.is_second_order()) {
    // w = y + (c/k) y' + y''/k holds for the stage's continuous input, which at the end of tick k
    // (where y_k is) is halfway between w_k and w_{k+1}: the held w_k is that input half a tick
    // earlier, y + (c/k - h) y' + (1/k - (c/k) h + h^2/2) y'' with h = dt/2, less the hold's
    // averaging over the tick, dt^2/24 y''.
    const double lag_s = stage_.second_order.c / stage_.second_order.k;
    const double half_tick_s = 0.5 * dt_s;
    lead_s_ = lag_s - half_tick_s;
    const double curvature_s2 =
        1.0 / stage_.second_order.k - lag_s * half_tick_s + 0.5 * half_tick_s * half_tick_s - dt_s * dt_s / 24.0;
    curvature_ = curvature_s2 / (dt_s * dt_s);
  }
}

std::optional<HysteresisSample> StageRemoval::reset() noexcept {
  forward_fresh_ = true;
  const bool held = have_ > 0;
  have_ = 0;
  if (!held) return std::nullopt;
  return HysteresisSample{u_prev_, y_prev_};
}

std::size_t StageRemoval::feed(double u_V, double y_m, HysteresisSample (&out)[2]) noexcept {
  if (!active()) {
    out[0] = {u_V, y_m};
    return 1;
  }
  if (!std::isfinite(u_V) || !std::isfinite(y_m)) {
    std::size_t n = 0;
    if (const auto held = reset()) out[n++] = *held;
    out[n++] = {u_V, y_m};
    return n;
  }
  if (!delays()) {  // stage then hysteresis: the hysteresis sees the stage's output
    if (forward_fresh_) {
      forward_.reset(u_V);
      forward_fresh_ = false;
    }
    out[0] = {forward_.step(u_V, dt_s_), y_m};
    return 1;
  }
  std::size_t n = 0;
  if (have_ == 1) {  // the held sample has no sample before it: a forward difference, no curvature
    out[n++] = {u_prev_, y_prev_ + lead_s_ * (y_m - y_prev_) / dt_s_};
  } else if (have_ == 2) {
    const double velocity_term = lead_s_ * (y_m - y_prev2_) / (2.0 * dt_s_);
    const double curvature_term = curvature_ * (y_m - 2.0 * y_prev_ + y_prev2_);
    out[n++] = {u_prev_, y_prev_ + velocity_term + curvature_term};
  }
  y_prev2_ = y_prev_;
  y_prev_ = y_m;
  u_prev_ = u_V;
  have_ = have_ < 2 ? have_ + 1 : 2;
  return n;
}

}  // namespace hystloop
