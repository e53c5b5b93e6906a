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

// What the servo's voltage (u_V - u_ff_V) has been doing lately, each a peak decaying over
// kMemory_s: how far it has reached above and below the feedforward, and its largest step per tick
// along the feedforward's own where that step is fast (at least fast_step_V: where the sum nears
// the slew limit). The plan leaves the servo a reserve of the slew limit
// (compensator.servo_slew_reserve, sized for noise and a line's start) and none of the range. A
// servo working hard against a model that is far off (its gain 1.5 times too high) pushes along
// the feedforward where the line is fastest, by several times the reserve, and the bridge would
// clamp the sum once a learned correction took the feedforward to the plan's limit. A servo that
// steps against the feedforward, or only at slow ticks, takes nothing of the slew limit from it;
// its reach above and below the feedforward takes its share of the range. The learned correction
// is held to what these peaks leave (FeedforwardPlanner). Samples of the bridge's safe state, or
// without the feedforward, tell nothing of the servo. Allocation- and lock-free.
class ServoActivity {
 public:
  static constexpr double kMemory_s = 0.5;  // two periods of a 4 Hz line; a 10 Hz line's five

  void observe(const CompensatorInput& sample, double dt_s, double fast_step_V) noexcept;
  void reset() noexcept { *this = ServoActivity{}; }
  // Decaying peaks [V]: of the servo's step along the feedforward's fast steps, and of how far its
  // voltage reached above (u - u_ff > 0) and below (u_ff - u > 0) the feedforward.
  double step_along_peak_V() const noexcept { return along_V_; }
  double above_peak_V() const noexcept { return above_V_; }
  double below_peak_V() const noexcept { return below_V_; }

 private:
  double along_V_ = 0.0, above_V_ = 0.0, below_V_ = 0.0;
  double last_fb_V_ = 0.0, last_ff_V_ = 0.0;
  std::int64_t seq_ = -1;       // the last sample with the servo's voltage known
  std::int64_t seen_seq_ = -1;  // the last sample of any kind (the peaks decay per tick, gaps included)
  double dt_s_ = 0.0, decay_ = 1.0;
};

}  // namespace hystloop
