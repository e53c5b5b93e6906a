#pragma once
// The built-in simulated stage (the bridge's default plant): Coleman–Hodgdon hysteresis and
// Banning's second-order stage in series, Tables 1 and 2 of Banning et al. (2001).
//
// Two orders are offered:
//   kHysteresisThenStage (default): u [V] -> CH -> w [m] -> stage -> y [m]. The piezo's
//     hysteresis drives the mechanics. The voltage is held over each step, hence so is w, and the
//     zero-order-hold stage is exact: the discrete model has no discretisation error at all.
//   kStageThenHysteresis: the paper's own connection (6)-(8): u [V] -> stage -> y_L [V] -> CH -> y.
//     Relation (25) and the magnitude estimate (27) are exact for this order. The stage is exact
//     (ZOH); the CH follows y_L at the step ends and, when y_L reverses inside a step, through the
//     extreme of its cubic Hermite interpolant (an O(dt^4) error at reversals only).
// At low frequency both reduce to the CH loop of Theorem 3.
//
// step(u, dt): u is held for dt [s]; returns y [m] at the end of the interval, times the gain
// scale (1 by default; the bridge drifts it to emulate a warming stage). Per-sample calls are
// noexcept and allocation free; a non-finite u or a dt that is not > 0 returns NaN and leaves the
// state untouched.

#include "models/coleman_hodgdon.hpp"
#include "models/second_order_stage.hpp"

namespace hystloop {

enum class BanningOrder { kHysteresisThenStage, kStageThenHysteresis };

struct BanningStageParams {
  ColemanHodgdonParams hysteresis;
  SecondOrderStageParams stage;
  BanningOrder order = BanningOrder::kHysteresisThenStage;

  // Throws ParameterError naming the field with its prefix ("hysteresis.alpha", "stage.k").
  void validate() const;
};

class BanningStage {
 public:
  explicit BanningStage(const BanningStageParams& params = {});  // validates

  // Equilibrium for the input held at u0 [V]: the CH output on its centre line a u0, stage at rest.
  void reset(double u0 = 0.0) noexcept;
  double step(double u, double dt) noexcept;  // u [V], dt [s] -> y [m]

  // Multiplies the output (not the state): takes effect at the next step. Returns false and
  // keeps the previous value unless scale is finite and > 0.
  bool set_gain_scale(double scale) noexcept;
  double gain_scale() const noexcept { return gain_scale_; }

  const BanningStageParams& params() const noexcept { return params_; }
  double output() const noexcept { return y_; }  // last y [m], gain scale included
  const ColemanHodgdon& hysteresis() const noexcept { return hysteresis_; }
  const SecondOrderStage& stage() const noexcept { return stage_; }

 private:
  BanningStageParams params_;
  ColemanHodgdon hysteresis_;
  SecondOrderStage stage_;
  double gain_scale_ = 1.0;
  double y_ = 0.0;
};

}  // namespace hystloop
