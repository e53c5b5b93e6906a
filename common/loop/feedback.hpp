#pragma once
// PID on the tracking error, added to the feedforward voltage. Gains are normalised by
// the stage's nominal gain so that they read in plain units whatever the stage:
//   u_fb [V] = N[(kp * e + ki * integral(e) + kd * de/dt) / nominal_gain_m_per_V],   e = y_ref - y [m]
// kp [-], ki [1/s], kd [s]. With the feedforward linearising the stage to ~unit gain,
// ki is roughly the loop's crossover in rad/s. N is up to two notches in cascade
// (notch_filter.hpp), one per lightly damped mode of the stage, which otherwise caps the loop's
// bandwidth: a stage under a load often has a second mode within the servo's reach (a flexure's
// first and second bending modes), and vendors' controllers offer two notches per axis for that.
//
// Anti-windup: each tick the caller says which total command u_ff + u_fb it will let through
// (the bridge: the actuator's range intersected with what the slew limit reaches from the last
// applied voltage). The integrator grows toward an edge of that interval only as far as the
// command stays inside it (conditional integration): it follows a clamped actuator instead of
// running ahead of it, so neither clamp winds it up, and a command the clamp cuts never has a
// grown integral behind it. With notches the edge holds for the next output and for the output
// the notches settle to (their gain at DC is 1), so their ringing cannot ratchet the integral up.

#include <array>
#include <cstddef>
#include <string>
#include <string_view>

#include "core/errors.hpp"
#include "loop/notch_filter.hpp"

namespace hystloop {

// Plausibility bounds on the gains (FeedbackGains::check_bounds), so that a gain the loop cannot
// use never reaches the actuator. The servo acts on the previous tick's error through the stage,
// whose gain is r x nominal_gain_m_per_V (r ~ 1; 0.57-1.36 over Banning's hysteresis loop):
//  - kp <= 2. On a stage that follows the voltage within a tick (no dynamics: the tick's delay
//    alone) a proportional servo multiplies the error by (1 - r kp) each tick, so above 2 / r it
//    diverges; only a stage's own lag lets more through, which a servo must not count on.
//    Banning's stage allows kp 0.40 without the notch (0.20 on a card that reads right after
//    writing) and 2.8 (1.2) with it: the bound is 5x the former, the default 0.1 is 20x inside.
//  - ki dt <= 1, dt = 1 / tick_rate_hz. The integral grows by ki dt of the error per tick; at 1 it
//    takes in a whole tick's error in one tick (deadbeat on a stage without dynamics), above it
//    over-corrects every tick. At 10 kHz: 10000 1/s, against the largest stable ki 9558 1/s (6172
//    on a card) with the default notch and kp; the default 2000 1/s is ki dt = 0.2.
//  - kd / (dt + 1 / (2 pi d_filter_hz)) <= 2: what the filtered derivative adds on the first tick
//    of an error step, which plays kp's part there, so kp's bound. 5.2e-4 s at the defaults (10 kHz,
//    a 1 kHz filter); Banning's stage allows 7.1e-4 s (derivative alone) with the notch, 1.5e-4 s
//    without.
inline constexpr double kMaxServoKp = 2.0;
inline constexpr double kMaxServoKiPerTick = 1.0;   // ki dt
inline constexpr double kMaxServoKdStepGain = 2.0;  // kd / (dt + 1 / (2 pi d_filter_hz))

// One notch of the servo's cascade: centre [Hz] (0 = none) and quality factor (centre / width) [-].
struct ServoNotch {
  double hz = 0.0;
  double q = 2.0;
  bool on() const noexcept { return hz > 0.0; }
};
inline constexpr std::size_t kServoNotches = 2;

struct FeedbackGains {
  double kp = 0.0;                       // [-]
  double ki = 0.0;                       // [1/s]
  double kd = 0.0;                       // [s]
  double nominal_gain_m_per_V = 6.4e-9;  // stage's mean slope dy/du (Banning stage: ~1.6 um / 250 V)
  double u_min_V = -250.0;               // the range of u_ff + u_fb the actuator allows (for anti-windup)
  double u_max_V = 250.0;
  double d_filter_hz = 1000.0;  // first-order low-pass on the derivative
  double notch_hz = 0.0;        // centre of the notch on the servo's output [Hz]; 0 = none
  double notch_q = 2.0;         // its quality factor, centre / width [-] (checked only with a notch)
  double notch2_hz = 0.0;       // a second notch in cascade with the first [Hz]; 0 = none
  double notch2_q = 2.0;        // its quality factor [-]
  double tick_rate_hz = 1e4;    // the rate update() is called at: the notch is designed for it
                                // (the bridge sets it from its clock, as it sets u_min_V/u_max_V)

  // Throws ParameterError naming the field ("servo.notch_hz", "servo.notch2_q"): each notch needs
  // 0 < notch_hz < 0.45 tick_rate_hz and notch_q in [0.1, 50].
  void validate() const;
  // validate(), then the plausibility bounds above: ParameterError naming the field (prefix +
  // "kp", "ki", "kd"), the value, the bound and why. Where gains enter (the bridge's config and
  // HX_CONTROL SET_GAINS, hystloop-ctl) and at FeedbackController::set_gains; not in validate(),
  // because the offline analysis (servo_loop_response.hpp) explores gains past them on purpose.
  void check_bounds(std::string_view prefix = "servo.") const;
  double max_kp() const noexcept { return kMaxServoKp; }
  double max_ki_per_s() const noexcept { return kMaxServoKiPerTick * tick_rate_hz; }
  double max_kd_s() const noexcept;
  bool enabled() const noexcept { return kp != 0.0 || ki != 0.0 || kd != 0.0; }
  bool has_notch() const noexcept { return notch_hz > 0.0; }
  bool has_notch2() const noexcept { return notch2_hz > 0.0; }
  // Notch i (0: the first, 1: the second) as {centre [Hz], q [-]}; centre 0 = none.
  ServoNotch notch(std::size_t i) const noexcept {
    return i == 0 ? ServoNotch{notch_hz, notch_q} : ServoNotch{notch2_hz, notch2_q};
  }
};

// "no notch", "notch at 780 Hz (Q 0.5)", "notches at 780 Hz (Q 0.5) and 2400 Hz (Q 1)": how
// start-up lines and tools name a servo's notches.
std::string notches_text(const FeedbackGains& g);

// The notch's limits (FeedbackGains::validate): below 0.45 of the tick rate the prewarped
// design is still a notch and not a band-stop pressed against Nyquist.
inline constexpr double kNotchMaxFractionOfRate = 0.45;
inline constexpr double kNotchMinQ = 0.1;
inline constexpr double kNotchMaxQ = 50.0;
// How far short of an edge of the allowed interval the integrator stops, per volt of the edge
// (plus 1 V): a nanovolt, far above the rounding of the command's sum, far below any DAC's step.
inline constexpr double kBoundaryMargin_V = 1e-9;

class FeedbackController {
 public:
  explicit FeedbackController(const FeedbackGains& gains = {});

  // Voltage correction for error e [m] after dt [s], given the feedforward part u_ff [V] and the
  // interval [u_lo_V, u_hi_V] the total command u_ff + u_fb will be clamped to (anti-windup).
  // Allocation- and throw-free. The notch steps once per call whatever dt (a skipped tick of the
  // clock is a rare overrun; the filter is designed for tick_rate_hz).
  double update(double error_m, double u_ff_V, double dt_s, double u_lo_V, double u_hi_V) noexcept;
  // The same against the actuator's range alone ([u_min_V, u_max_V]).
  double update(double error_m, double u_ff_V, double dt_s) noexcept {
    return update(error_m, u_ff_V, dt_s, gains_.u_min_V, gains_.u_max_V);
  }

  // New gains (check_bounds: a run-time change is refused outside the plausibility bounds, the
  // gains in force stay); the integral is rescaled so that its part of the output does not jump,
  // a changed notch starts settled at its own last output and an unchanged one keeps its state
  // (bumpless).
  void set_gains(const FeedbackGains& gains);
  const FeedbackGains& gains() const noexcept { return gains_; }
  void reset() noexcept;
  double integral_m_s() const noexcept { return integral_; }

 private:
  FeedbackGains gains_;
  std::array<NotchFilter, kServoNotches> notches_;   // in cascade; a filter for a notch off is the identity
  std::array<double, kServoNotches> notch_out_V_{};  // each filter's last output (a changed one settles there)
  double integral_ = 0.0;                            // [m s]
  double prev_error_ = 0.0;
  double d_state_ = 0.0;   // filtered derivative [m/s]
  double output_V_ = 0.0;  // the last correction returned
  bool has_prev_ = false;
};

}  // namespace hystloop
