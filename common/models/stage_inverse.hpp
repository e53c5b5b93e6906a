#pragma once
// The linear stage in series with the hysteresis, sampled at the bridge's tick, and its exact
// inverse: what the feedforward must put into the stage so that the position at the end of every
// tick is the reference.
//
// Banning's stage y'' + c y' + k y = k w (models/second_order_stage.hpp) with its input held over
// each tick (the DAC's zero-order hold) is, at the tick ends, exactly
//
//   Y_k = -a1 Y_{k-1} - a2 Y_{k-2} + b1 w_k + b2 w_{k-1},     Y_k = y at the end of tick k,
//
// i.e. G(z) = (b1 z + b2) / (z^2 + a1 z + a2) with one tick of delay. Its zero, z0 = -b2 / b1, is
// the sampling zero that every ZOH model of relative degree two has (about -0.93 for Banning's
// 1.72 kHz, zeta 0.094 stage at 10 kHz); it lies inside the unit circle for every k, c > 0, on
// it only in the undamped limit. The inverse
//
//   w_k = (r_k + a1 r_{k-1} + a2 r_{k-2} - b2 w_{k-1}) / b1
//
// is therefore causal and stable, and exact at the samples: driven by it the stage reproduces r at
// every tick end (to rounding). It needs no preview, because the compensator's convention already
// aims the command of tick k at the position at the end of tick k. Its one pole is z0: the closer
// z0 is to -1, the longer it rings at half the tick rate and the more it amplifies what the
// reference has there, so a stage with |z0| > kMaxSamplingZero is refused rather than inverted
// (a ZPETC or a non-causal inverse over the plan's horizon would be the way to go beyond;
// docs/TRACKING.md says why this one was chosen).
//
// The same class serves both orders of Banning et al.: hysteresis then stage (w in metres, the
// hysteresis model's output) and stage then hysteresis (w in volts, the stage's input); the stage
// has unit DC gain, so the unit of w is the unit of r.

#include <cstdint>

#include "models/banning_stage.hpp"
#include "models/linear_stage.hpp"
#include "models/second_order_stage.hpp"

namespace hystloop {

struct DiscreteStage {
  double a1 = 0.0;  // denominator z^2 + a1 z + a2
  double a2 = 0.0;
  double b1 = 0.0;  // numerator b1 z + b2
  double b2 = 0.0;

  double sampling_zero() const noexcept { return -b2 / b1; }
  // |G| at frequency f [Hz] for tick dt [s] (the magnitude the inverse divides by).
  double magnitude(double f_hz, double dt_s) const noexcept;
};

// The exact ZOH discretisation of `stage` at tick dt_s (the same matrix exponential as
// SecondOrderStage::step, so the two agree to rounding). Validates both (ParameterError).
DiscreteStage discretise_zoh(const SecondOrderStageParams& stage, double dt_s);

// The stage a feedforward inverts beside the hysteresis: none (a plant without dynamics, such as
// the Ramberg-Osgood backend), Banning's second order in either order (inverted causally, below),
// or a linear stage of any order with an input delay (models/linear_stage.hpp: the forms a lab's
// identification prints), inverted with the plan's preview (models/preview_inverse.hpp), in the
// order hysteresis then stage only: the preview runs the reference ahead of the hysteresis inverse.
struct StageModel {
  enum class Kind : std::int8_t { kNone = 0, kSecondOrder = 1, kLinear = 2 };
  Kind kind = Kind::kNone;
  SecondOrderStageParams second_order{};
  LinearStageSpec linear{};
  BanningOrder order = BanningOrder::kHysteresisThenStage;
  // kLinear: the reference's preview the inverse takes (0: the shortest that meets the inverse's
  // truncation bound), and its optional zero-phase low-pass (0: off; PreviewStageInverse).
  std::int64_t preview_ticks = 0;
  double reference_bandwidth_hz = 0.0;
  // kLinear: the frequency [Hz] up to which the stage's identification measured this model within
  // kStageKnownWithin of the record (0: not said; hystloop-identify --model stage writes it). What
  // learning may go up to beside the stage (loop/compensator_config.hpp, learning_for_stage).
  double known_to_hz = 0.0;

  bool has_dynamics() const noexcept { return kind != Kind::kNone; }
  bool is_second_order() const noexcept { return kind == Kind::kSecondOrder; }
  bool is_linear() const noexcept { return kind == Kind::kLinear; }
  // Throws ParameterError naming "stage.k", "stage.c" (also when it cannot be inverted stably
  // at tick dt_s, see StageInverse), or the linear stage's field ("stage.poles[1]", "stage.delay_s",
  // "stage.preview_ticks" when the preview is too short to invert it).
  void validate(double dt_s) const;
  // The stage's lowest resonance [rad/s] (0: none): what corner roundings and servo notches start
  // from. Of the complex poles (with_zeros: and the complex zeros of a linear stage) whose damping
  // ratio is under max_damping, the lowest natural frequency, from the stage sampled at dt_s.
  double lowest_resonance_rad_s(double dt_s, bool with_zeros = false, double max_damping = 1.0) const;
};

// The preview a linear stage's inverse needs at tick dt_s: `wanted` when it is enough (throws the
// inverse's ParameterError naming the preview needed otherwise), or with wanted 0 the shortest that
// meets the truncation bound (throws when none up to PreviewStageInverse::kMaxPreviewTicks does).
std::int64_t stage_preview_ticks(const DiscreteLinearStage& stage, std::int64_t wanted, double reference_bandwidth_hz);

class StageInverse {
 public:
  static constexpr double kMaxSamplingZero = 0.98;

  // Throws ParameterError ("stage.c") when the stage's sampling zero at this tick has
  // |z0| > kMaxSamplingZero, naming z0 and what to do.
  StageInverse(const SecondOrderStageParams& stage, double dt_s);

  // At rest at y0: the reference has been y0 for ever and so has the input.
  void reset(double y0) noexcept;
  // The stage input for tick k from the reference r_k of that tick. Allocation- and throw-free;
  // a non-finite r_k returns the last input and leaves the state untouched.
  double step(double r_k) noexcept;
  double last_input() const noexcept { return w_prev_; }

  const DiscreteStage& model() const noexcept { return model_; }
  const SecondOrderStageParams& params() const noexcept { return params_; }

 private:
  SecondOrderStageParams params_;
  DiscreteStage model_;
  double r1_ = 0.0;  // r_{k-1}
  double r2_ = 0.0;  // r_{k-2}
  double w_prev_ = 0.0;
};

}  // namespace hystloop
