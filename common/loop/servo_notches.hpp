#pragma once
// Notches for the servo from a stage model: one per lightly damped mode whose resonance lifts the
// stage's gain above its DC gain, the most resonant first, as many as the servo has
// (kServoNotches). What `hystloop-identify --model stage` prints beside an identified stage, and
// what deploy/config/two-mode's servo was set from.
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

#include <complex>
#include <functional>
#include <span>
#include <vector>

#include "loop/feedback.hpp"
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

}  // namespace hystloop
