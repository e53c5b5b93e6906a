#pragma once
// A stage's linear dynamics measured through its hysteresis: the series model u -> H -> G -> y
// fitted so that together they explain the record, not the best linear approximation of the whole.
//
// Why: the frequency response from u to y (frequency_response.hpp) is the stage times the
// hysteresis' best linear approximation (BLA), and a fit of it must find the actuator's gain beside
// the stage's modes, a free parameter the noise moves where the response is weakest: at an
// anti-resonance, where the modes nearly cancel. Measured (bench/stage_identification_table, the
// default stage experiment of 24 realisations of 5 periods, five draws of 1 nm noise): behind the
// two-mode stage the worst error, at its 1.85 kHz anti-resonance, is 0.67 dB median from u -> y and
// 0.43 dB through the hysteresis, lower or level in the median on the table's other plants (within
// the draws' spread where higher); without noise both are within 0.06 dB of the truth (the BLA's
// own bias on Coleman-Hodgdon's loops is that small). So what the series model buys is the gain
// set by the hysteresis over every line of the record, and a stage with unit DC gain fitted to the
// hysteresis' output; what limits the anti-resonance after that is the noise and the hysteresis'
// distortion, both averaged over realisations (docs/TRACKING.md, "Measuring a stage").
//
// Method (an alternating, separable fit): H is a Prandtl-Ishlinskii model, y_H = sum_i w_i F_ri[u],
// linear in its weights w_i >= 0 (the play operators F_ri of pi_fit.hpp, thresholds evenly spaced to
// half the record's input span), so for a fixed stage G the record is linear in the weights:
//   Y_r(k) = sum_i w_i G(k) P_ri(k)     for every DFT line k up to the highest excited one,
// with Y_r the mean over realisation r's steady periods and P_ri the play outputs' spectra (the
// plays are periodic once the input has swept its range). NNLS on those lines (real and imaginary
// parts, every realisation) gives the weights; then w = H(u) over the whole record is the stage's
// input, and the robust method's FRF from w to y (its noise and distortion levels from periods and
// realisations, as for u -> y) is fitted by fit_stage_model as before. Start: G from u -> y (its
// order given or chosen there, then kept); then `iterations` rounds. The lines between the excited ones carry the
// hysteresis' distortion, and fit the weights too. The fitted G has unit DC gain when H carries the stage's gain (H in
// metres).

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "ident/frequency_response.hpp"
#include "ident/stage_fit.hpp"
#include "ident/stage_identification.hpp"

namespace hystloop {

struct HysteresisStageOptions {
  std::size_t operators = 15;  // play operators of H (1 .. kPiMaxOperators)
  // Rounds of (weights, stage) after the first stage fit. Two: on the two-mode stage the worst error
  // goes 0.74, 0.71, 0.70 dB over one, two, three (bench/stage_identification_table with 8 realisations
  // of 9 periods, median of five).
  int iterations = 2;
  void validate() const;  // throws ParameterError naming the field
};

struct HysteresisStageIdentification {
  StageIdentification stage;         // the last round's: FRF from w = H(u) to y, and its fit (its
                                     // `orders`: the u -> y search that chose the order)
  StageIdentification linear;        // the first: u -> y, the BLA's (what identify_stage_dynamics gives)
  std::vector<double> thresholds_V;  // H's plays
  std::vector<double> weights;       // [m/V] >= 0; H = sign(u -> y DC gain) sum_i w_i F_ri[u]
  std::vector<double> w;             // H(u) over the record, u's layout [m]
  // RMS over the steady periods' mean (per realisation) of y - G(H(u)) and of y - G_BLA u, on the
  // lines up to the highest excited one [y's unit]: what the series model leaves against the BLA.
  double residual_rms = 0.0;
  double residual_rms_linear = 0.0;
  // Rounds that gave a stage (fewer than asked when one failed or was not kept: stage is then the
  // last good round's; 0: none did, and stage is the u -> y fit, or, when the first round's fit
  // failed, that failure)
  int rounds = 0;
  // A round whose series model leaves more than kKeptResidualRatio times u -> y's residual is not
  // kept, and the rounds end there: why (empty when every round was kept).
  static constexpr double kKeptResidualRatio = 1.1;
  std::string not_kept;
  bool ok() const noexcept { return stage.ok(); }
};

// u [V], y [m] as identify_stage_dynamics takes them (same options; fit_options.unit_dc_gain is set
// false for the first fit, true for the rest, where H carries the gain). Throws ParameterError for
// bad options; bad data come back as !ok() with a reason.
HysteresisStageIdentification identify_stage_with_hysteresis(std::span<const double> u, std::span<const double> y,
                                                             std::span<const std::size_t> lines,
                                                             const FrfOptions& frf_options, StageFitOptions fit_options,
                                                             bool sampled_at_tick_end,
                                                             const HysteresisStageOptions& options = {});

}  // namespace hystloop
