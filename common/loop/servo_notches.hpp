#pragma once
// A servo from a stage model: its notches and its integral gain (servo_for_stage, below). The
// notches: one per lightly damped mode whose resonance lifts the stage's gain above its DC gain,
// the most resonant first, as many as the servo has (kServoNotches). What `hystloop-identify
// --model stage` prints beside an identified stage, and what deploy/config/two-mode's servo was
// set from.
//
// The rule, per complex pole pair p (|p| = w, damping zeta = -Re p / w):
//  - lightly damped: zeta < kNotchMaxDamping (0.2; above it a mode barely peaks);
//  - below kNotchMaxFractionOfRate (0.45) of the tick rate (a notch there is still a notch);
//  - peak = |G(j w)| / |G(0)| > 1: the resonance lifts the loop's gain (a mode whose residue is
//    small against the others' roll-off is not worth the notch's phase);
//  - the notch at w / 2 pi, the narrowest (the highest Q) that still takes the peak down to unity
//    10 % off the centre, where the mode of a stage under another load, or of a model 10 % off, sits:
//      |N(1.1 w)| peak = 1,  N the notch,  so  Q = 1.1 / sqrt(0.21^2 (peak^2 - 1)),
//    clamped to [kNotchMinQ, kNotchMaxSuggestedQ]. A wide notch costs phase below its centre; the
//    margins (servo_loop_response.hpp) say whether the servo's gains still hold with it.

#include <array>
#include <complex>
#include <functional>
#include <span>
#include <vector>

#include "loop/feedback.hpp"
#include "loop/servo_loop_response.hpp"
#include "models/linear_stage.hpp"

namespace hystloop {

inline constexpr double kNotchMaxDamping = 0.2;
inline constexpr double kNotchDetuning = 0.1;       // the mode may sit this fraction off the notch
inline constexpr double kNotchMaxSuggestedQ = 5.0;  // narrower is fragile to any drift of the mode

struct ModeNotch {
  ServoNotch notch;
  double damping = 0.0;    // the mode's [-]
  double peak_gain = 0.0;  // |G(j w)| / |G(0)| [-]
};

// `response_hz(f)`: the stage's response at f [Hz] (any DC gain). Poles [rad/s], each conjugate
// pair once or twice (the one with Im > 0 is taken). Sorted by peak gain, at most kServoNotches.
std::vector<ModeNotch> notches_for_stage(std::span<const std::complex<double>> poles_rad_s,
                                         const std::function<std::complex<double>(double)>& response_hz,
                                         double tick_rate_hz);
// The same for a model in the forms of models/linear_stage.hpp (a discrete form (d): its poles
// mapped back by s = ln(z) / dt). Validates the model at the tick (ParameterError).
std::vector<ModeNotch> notches_for_stage(const LinearStageSpec& stage, double tick_rate_hz);

// The notches into a servo's gains: the first into notch_hz/notch_q, the second into notch2_*;
// a notch not suggested is removed (0 Hz).
void set_notches(FeedbackGains& gains, std::span<const ModeNotch> notches) noexcept;

// A servo for a stage model: its notches (above), no proportional or derivative term (beside
// lightly damped modes they lift the loop's gain at every frequency the notches leave, and the
// feedforward does the tracking: the servo takes out what it leaves), and the largest integral gain
// whose loop keeps kServoDesignGainMargin_dB and kServoDesignPhaseMargin_deg at both ends of the
// hysteresis' local slope (kServoDesignSlopeRatios of the nominal gain: Banning's stage moves
// between about 0.6 and 1.4) with extra_delay_ticks beyond the simulator's (1: a card that reads after
// it writes). Those margins are above the 6 dB / 40 deg hystloop-ctl gains warns under, by what a
// model 10 % off in a mode or 1.5 times off in gain costs. What `hystloop-identify --model stage`
// suggests; `base` gives the rest of the gains (limits, tick rate, nominal gain).
inline constexpr double kServoDesignGainMargin_dB = 10.0;
inline constexpr double kServoDesignPhaseMargin_deg = 50.0;
inline constexpr std::array<double, 2> kServoDesignSlopeRatios = {0.6, 1.4};

struct StageServo {
  FeedbackGains gains;             // base with kp = kd = 0, the notches and ki [1/s, whole] (0: none holds)
  std::vector<ModeNotch> notches;  // as notches_for_stage found them
  LoopMargins worst;               // the smaller margins over the slope ratios, at that ki
};
// Validates the model at the tick (ParameterError).
StageServo servo_for_stage(const LinearStageSpec& stage, FeedbackGains base, int extra_delay_ticks = 0);

}  // namespace hystloop
