#pragma once
// The hysteresis' own input and output from what the loop measures, for a fit of the hysteresis
// alone when a stage with dynamics sits in series with it (Banning et al.'s second order,
// y'' + c y' + k y = k w). At line rates the stage matters to a fit: the position at a tick's end
// is a third of a tick off the voltage held over it (the hold's half tick less the stage's lag,
// c / k = 17 us), 10 nm of a 0.5 um sine at 100 Hz, which a fit of u -> y reads as hysteresis
// and the compensator, inverting the stage itself, would then correct twice.
//  - hysteresis then stage (y = G(H(u))): the hysteresis' output is the stage's input,
//    w = y + (c / k) y' + y'' / k, from central differences over the neighbouring samples (so a
//    sample is given out one sample late) and moved to the middle of the tick, where the held
//    input w_k stands (y_k is at the tick's end: without the move, half a tick, 16 nm of a 0.5 um
//    sine at 100 Hz, would be left). What is left is third order in the signal's frequency
//    (0.4 nm of 0.5 um at 200 Hz). Not the exact inverse of the sampled stage that the
//    compensator runs (models/stage_inverse.hpp): that one's pole at the sampling zero (z = -0.93)
//    turns 1 nm of sensor noise into ~70 nm at half the tick rate; the differences leave it at
//    1.4 nm.
//  - stage then hysteresis (y = H(G(u))): the hysteresis' input is the stage's output, G(u),
//    the exact sampled stage driven by u (causal, no delay, no noise).
// Kind none passes the samples through, and so (not yet removed) does a linear stage of any order:
// a fit behind one reads its dynamics as hysteresis. A break in the stream (reset()) hands out the held
// sample as measured and starts again; a non-finite sample passes through (the estimator counts
// it as poison) and is a break too. Allocation- and throw-free after construction.

#include <cstddef>
#include <optional>
#include <utility>

#include "models/second_order_stage.hpp"
#include "models/stage_inverse.hpp"

namespace hystloop {

struct HysteresisSample {
  double u = 0.0;  // the hysteresis' input [V]
  double y = 0.0;  // its output [m]
};

class StageRemoval {
 public:
  StageRemoval(const StageModel& stage, double dt_s);  // validated by the caller (StageModel::validate)

  // Sample (u, y) of the next tick. Writes into out what is ready (0, 1 or 2 samples: a held one
  // and, for a non-finite sample, the sample itself) and returns how many.
  std::size_t feed(double u_V, double y_m, HysteresisSample (&out)[2]) noexcept;
  // The stream breaks (a gap, a skipped tick): the held sample, if any, as measured.
  std::optional<HysteresisSample> reset() noexcept;

  bool active() const noexcept { return stage_.is_second_order(); }
  // One sample late (hysteresis then stage): feed() returns the sample before.
  bool delays() const noexcept { return active() && stage_.order == BanningOrder::kHysteresisThenStage; }

 private:
  StageModel stage_;
  double dt_s_;
  double lead_s_ = 0.0;       // weight of y' [s]
  double curvature_ = 0.0;    // weight of y'' over dt^2 [-]
  SecondOrderStage forward_;  // stage then hysteresis
  bool forward_fresh_ = true;
  // hysteresis then stage: the two samples before (y_prev2_ only when have_ == 2) and u of the held one
  int have_ = 0;
  double y_prev2_ = 0.0, y_prev_ = 0.0, u_prev_ = 0.0;
};

}  // namespace hystloop
