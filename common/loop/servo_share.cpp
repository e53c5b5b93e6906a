#include "loop/servo_share.hpp"

#include <algorithm>
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

void ServoActivity::observe(const CompensatorInput& sample, double dt_s, double fast_step_V) noexcept {
  if (dt_s != dt_s_) {
    dt_s_ = dt_s;
    decay_ = std::exp(-dt_s / kMemory_s);
  }
  const std::int64_t ticks = seen_seq_ >= 0 && sample.seq > seen_seq_ ? sample.seq - seen_seq_ : 1;
  seen_seq_ = sample.seq;
  const double decay = ticks == 1 ? decay_ : std::pow(decay_, static_cast<double>(ticks));
  along_V_ *= decay;
  above_V_ *= decay;
  below_V_ *= decay;
  const double fb = sample.u_V - sample.u_ff_V;
  if (sample.safe_state || !std::isfinite(fb)) {
    seq_ = -1;
    return;
  }
  if (seq_ >= 0 && sample.seq == seq_ + 1) {
    const double ff_step = sample.u_ff_V - last_ff_V_;
    if (std::abs(ff_step) >= fast_step_V)
      along_V_ = std::max(along_V_, std::copysign(1.0, ff_step) * (fb - last_fb_V_));
  }
  above_V_ = std::max(above_V_, fb);
  below_V_ = std::max(below_V_, -fb);
  last_fb_V_ = fb;
  last_ff_V_ = sample.u_ff_V;
  seq_ = sample.seq;
}

}  // namespace hystloop
