#pragma once
// The position the servo's voltage bought, taken out of each measurement before the learning sees
// it. The learning corrects the feedforward, so it must see the feedforward's own error. The servo
// on y_ref - y works against every correction (what reaches the position is the correction times
// the loop's sensitivity S, 0.16 at 50 Hz with the default gains), which would slow the learning
// to a crawl where S is small and leave the update's premise, a plant from correction to position
// near 1, untrue. The stage (linearised at the linear model's gain) driven by u_V - u_ff_V is the
// servo's share: what is left of the measurement is y_ff, the position the feedforward alone would
// have made, and r - y_ff is what the learning removes. Noise is untouched (it enters y, not u_ff),
// so the learner's noise bound holds as is.

#include <cstdint>
#include <optional>

#include "loop/compensator_config.hpp"
#include "models/linear_stage.hpp"
#include "models/second_order_stage.hpp"

namespace hystloop {

class ServoShare {
 public:
  // The stage the servo's voltage drives: Banning's second order, a linear stage sampled at the
  // tick, or neither (the gain alone). Starts again at the next sample.
  void set_second_order(const SecondOrderStageParams& params);
  void set_linear(const DiscreteLinearStage& sampled);
  void set_none() noexcept;

  // The servo's share of the position [m] at this sample: gain_m_per_V (u_V - u_ff_V) through the
  // stage, which restarts at rest there after a sample missed; 0 when u_ff_V is not known (NaN).
  double position_m(const CompensatorInput& sample, double gain_m_per_V, double dt_s) noexcept;

 private:
  std::optional<SecondOrderStage> second_order_;
  std::optional<LinearStageSimulator> linear_;
  std::int64_t seq_ = -1;  // the last sample it was stepped with
};

}  // namespace hystloop
