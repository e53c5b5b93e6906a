#pragma once
// The hysteresis' own input and output from what the loop measures, for a fit of the hysteresis
// alone when a stage with dynamics sits in series with it. At line rates the stage matters to a
// fit: with Banning et al.'s second order (y'' + c y' + k y = k w) the position at a tick's end is
// a third of a tick off the voltage held over it (the hold's half tick less the stage's lag,
// c / k = 17 us), 10 nm of a 0.5 um sine at 100 Hz, which a fit of u -> y reads as hysteresis
// and the compensator, inverting the stage itself, would then correct twice.
//  - hysteresis then stage (y = G(H(u))): the hysteresis' output is the stage's input,
//    w_k = y_{k+d} + lead y'_{k+d} + curvature dt^2 y''_{k+d}, from central differences over the
//    neighbouring samples, d + 1 samples late. The whole ticks d of a linear stage's input delay
//    (models/linear_stage.hpp; 0 for Banning's) are taken out exactly by that shift, so a long
//    delay (up to LinearStageSpec::kMaxDelayTicks) costs nothing in accuracy. The rest, G(q) with
//    q = z^-1 (its fractional delay included), by its moments at DC, m1 = G'(1) / G(1),
//    m2 = (G''(1) + G'(1)) / G(1): G(e^{s dt}) = 1 - m1 dt s + m2 dt^2 s^2 / 2 + O(s^3), so
//    1 / G = 1 + a1 s + a2 s^2 with lead = a1 = m1 dt, curvature = a2 / dt^2 = m1^2 - m2 / 2
//    (removal_terms()). What is left is third order in the signal's frequency: the third-order
//    term of 1 / G with the differences' own error, c3 (2 pi f dt)^3 of the amplitude
//    (tests/ident/stage_removal_test.cpp derives the bound per stage and holds the removal to it).
//    For Banning's stage (its sampled model's moments; the continuous w = y + (c / k) y' + y'' / k
//    moved half a tick back to where the held w_k stands is within 0.1 % of them) that is 0.4 nm
//    of a 0.5 um sine at 200 Hz; for the two-mode stage of sim/tracking_experiment.cpp 0.2 nm.
//    Not the exact inverse of the sampled stage that the compensator runs (models/stage_inverse.hpp,
//    preview_inverse.hpp): for Banning's its pole at the sampling zero (z = -0.93) turns 1 nm of
//    sensor noise into ~70 nm at half the tick rate; the differences leave it at 1.4 nm (8.6 nm
//    for the two-mode stage: its 780 Hz mode makes the curvature 3.8, Banning's 0.86; white, it
//    averages out of a fit's least squares, where the stage's lag would not).
//  - stage then hysteresis (y = H(G(u)), Banning's stage only): the hysteresis' input is the
//    stage's output, G(u), the exact sampled stage driven by u (causal, no delay, no noise).
// Kind none passes the samples through.
//
// A break in the stream (reset()) hands out at most one sample: the oldest held one, k = n - d
// (n the last sample fed), with the position measured d ticks after it, y_n, and no derivative
// terms (its later neighbour never came). The d younger held samples are dropped: the stage's
// response to them was never measured, and pairing their inputs with earlier positions is the
// delay a fit must not see. After a break the next d + 1 samples are held again. A non-finite
// sample passes through (the estimator counts it as poison) and is a break too.
// Allocation- and throw-free after construction (the held inputs are in a fixed ring of
// LinearStageSpec::kMaxDelayTicks + 2).

#include <array>
#include <cstddef>
#include <optional>
#include <utility>

#include "models/linear_stage.hpp"
#include "models/second_order_stage.hpp"
#include "models/stage_inverse.hpp"

namespace hystloop {

struct HysteresisSample {
  double u = 0.0;  // the hysteresis' input [V]
  double y = 0.0;  // its output [m]
};

// How the removal recovers a linear stage's input: w_k = y_{k+d} + lead_s y'_{k+d} +
// curvature dt^2 y''_{k+d}, from the sampled model's moments (above).
struct StageRemovalTerms {
  int delay_ticks = 0;     // d: the whole ticks, shifted out exactly
  double lead_s = 0.0;     // weight of y' [s]
  double curvature = 0.0;  // weight of y'' over dt^2 [-]
};
StageRemovalTerms removal_terms(const DiscreteLinearStage& stage) noexcept;

class StageRemoval {
 public:
  // Validated by the caller (StageModel::validate); a linear stage is sampled here (discretise,
  // which throws ParameterError for one it refuses).
  StageRemoval(const StageModel& stage, double dt_s);

  // Sample (u, y) of the next tick. Writes into out what is ready (0, 1 or 2 samples: a held one
  // and, for a non-finite sample, the sample itself) and returns how many.
  std::size_t feed(double u_V, double y_m, HysteresisSample (&out)[2]) noexcept;
  // The stream breaks (a gap, a skipped tick): the oldest held sample, if any, with the last
  // measured position (see above); the others held are dropped.
  std::optional<HysteresisSample> reset() noexcept;

  bool active() const noexcept { return stage_.is_second_order() || stage_.is_linear(); }
  // Late (hysteresis then stage): feed() returns the sample delay_samples() before.
  bool delays() const noexcept { return active() && stage_.order == BanningOrder::kHysteresisThenStage; }
  int delay_samples() const noexcept { return delays() ? delay_ticks_ + 1 : 0; }
  double lead_s() const noexcept { return lead_s_; }
  double curvature() const noexcept { return curvature_; }

 private:
  static constexpr int kRing = DiscreteLinearStage::kMaxDelayTicks + 2;

  StageModel stage_;
  double dt_s_;
  int delay_ticks_ = 0;       // whole ticks of the linear stage's delay (0 for Banning's)
  double lead_s_ = 0.0;       // weight of y' [s]
  double curvature_ = 0.0;    // weight of y'' over dt^2 [-]
  SecondOrderStage forward_;  // stage then hysteresis
  bool forward_fresh_ = true;
  // hysteresis then stage: the inputs u of the samples held (delay_ticks_ + 2 slots, the newest at
  // head_ - 1), the last two positions (y_prev2_ only when fed_ >= 2), and the samples fed since
  // the last break (counted up to delay_ticks_ + 3, which is all that is asked of it).
  std::array<double, kRing> u_held_{};
  int head_ = 0;
  int fed_ = 0;
  double y_prev2_ = 0.0, y_prev_ = 0.0;
};

}  // namespace hystloop
