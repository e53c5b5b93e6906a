#include "loop/servo_share.hpp"

#include <cmath>

namespace hystloop {

void ServoShare::set_second_order(const SecondOrderStageParams& params) {
  set_none();
  second_order_.emplace(params);
}

void ServoShare::set_linear(const DiscreteLinearStage& sampled) {
  set_none();
  linear_.emplace(sampled);
}

void ServoShare::set_none() noexcept {
  second_order_.reset();
  linear_.reset();
  seq_ = -1;
}

double ServoShare::position_m(const CompensatorInput& sample, double gain_m_per_V, double dt_s) noexcept {
  const double du = sample.u_V - sample.u_ff_V;
  const bool consecutive = seq_ >= 0 && sample.seq == seq_ + 1;
  seq_ = sample.seq;
  if (!std::isfinite(du)) return 0.0;
  const double w = gain_m_per_V * du;
  if (linear_) {
    if (!consecutive) linear_->reset(w);
    return linear_->step(w);
  }
  if (!second_order_) return w;
  if (!consecutive) second_order_->reset(w);
  return second_order_->step(w, dt_s);
}

}  // namespace hystloop
