#pragma once
// The bridge's servo loop as a discrete linear system, for choosing its gains: the loop gain
//   L(z) = r * N(z) * C(z) * P(z) * z^-d
// with P the exact zero-order-hold discretisation of the second-order stage, or of any linear stage
// with its delay (ServoLoopModel::linear), (unit DC gain; it
// includes the tick between a voltage and the position sampled at the tick's end, what the
// simulator hands the next tick), C the PID of FeedbackController (backward-Euler integral, the
// filtered backward-difference derivative), N its notches in cascade, r the stage's local slope over
// nominal_gain_m_per_V (the hysteresis makes it move: Banning's stage from ~0.6 to ~1.4), and d
// extra ticks of delay (1 on a card that reads the sensor right after writing the voltage: the
// position then reaches the servo a tick later than in the simulator).
//
// Offline analysis (it allocates): margins, sensitivity and closed-loop poles, computed from
// the same SecondOrderStage the simulator steps, so the figures are the simulated loop's.

#include <complex>
#include <optional>
#include <vector>

#include "loop/feedback.hpp"
#include "models/linear_stage.hpp"
#include "models/second_order_stage.hpp"

namespace hystloop {

struct ServoLoopModel {
  SecondOrderStageParams stage{};  // Banning et al., Table 2
  // Any other stage (models/linear_stage.hpp: modes, zeros and poles, a delay), in place of
  // `stage` when set: P is then its exact sampled model, with the same tick before the servo sees
  // the position.
  std::optional<LinearStageSpec> linear;
  double dt_s = 1e-4;         // the tick
  double slope_ratio = 1.0;   // the stage's local dy/du over the servo's nominal gain [-]
  int extra_delay_ticks = 0;  // beyond the ZOH's tick (0: the simulator; 1: read-after-write on a card)

  void validate() const;  // throws ParameterError naming the field
};

struct LoopMargins {
  bool stable = false;               // every closed-loop pole inside the unit circle
  double max_pole_radius = 0.0;      // of the closed loop [-]
  double gain_margin_dB = 0.0;       // smallest, over every crossing of the negative real axis (+inf: none)
  double gain_margin_hz = 0.0;       // where (NaN: none)
  double phase_margin_deg = 0.0;     // smallest, over every crossing of |L| = 1 (+inf: none)
  double crossover_hz = 0.0;         // the lowest gain crossover (NaN: none)
  double sensitivity_peak = 0.0;     // max |S| = 1 / (distance of L from -1), up to Nyquist
  double sensitivity_peak_hz = 0.0;  // where
};

class ServoLoopResponse {
 public:
  // The gains as the bridge would run them (tick_rate_hz is taken from model.dt_s).
  ServoLoopResponse(const FeedbackGains& gains, const ServoLoopModel& model = {});

  std::complex<double> loop_gain(double f_hz) const;  // L(e^{j 2 pi f dt})
  double sensitivity(double f_hz) const;              // |1 / (1 + L)|: the error left of a disturbance at f
  std::vector<std::complex<double>> closed_loop_poles() const;
  bool stable() const;  // every closed-loop pole inside the unit circle
  LoopMargins margins() const;

 private:
  // Polynomials in z^-1, lowest power first.
  std::vector<double> num_, den_;
  double dt_s_;
};

// The largest ki (to within tol_per_s) up to which the loop with the other gains of `gains` is
// stable: the first stability boundary above ki = 0 (scanned in 2 % steps, then bisected), or
// ki_max_per_s when there is none below it; 0 when the loop is unstable at the smallest ki.
double largest_stable_ki(FeedbackGains gains, const ServoLoopModel& model, double ki_max_per_s = 1e5,
                         double tol_per_s = 1.0);

}  // namespace hystloop
