#pragma once
// The servo's margins for a set of gains before they are sent (hystloop-ctl gains): the loop of
// loop/servo_loop_response.hpp on the stage model the compensator inverts (its `stage:` section,
// Banning's second order or any linear stage with its delay). Below the usual bounds of a
// precision-motion servo (6 dB gain margin, 40 degrees phase margin) the gains are sent with a
// warning; gains the loop is unstable with are refused unless forced.

#include <optional>
#include <string>
#include <vector>

#include "lcm/servo_gains_status.hpp"
#include "loop/servo_loop_response.hpp"
#include "models/stage_inverse.hpp"

namespace hystloop::ctl {

inline constexpr double kMinGainMargin_dB = 6.0;
inline constexpr double kMinPhaseMargin_deg = 40.0;

struct ServoCheck {
  LoopMargins margins;
  std::vector<std::string> warnings;  // each bound the loop misses, and instability
  bool stable() const noexcept { return margins.stable; }
};

// The loop model of a stage: nullopt for a stage without dynamics (kind none: nothing to check
// against). dt_s: the servo's tick; extra_delay_ticks: a card's read after its write (1), beyond
// the tick the simulator takes.
std::optional<ServoLoopModel> servo_loop_model(const StageModel& stage, double dt_s, int extra_delay_ticks);

// The servo's gains as the bridge reports them, as the controller's (at the default rig's tick rate).
FeedbackGains servo_gains(const ServoGainsFigures& gains);

ServoCheck check_servo(const ServoGainsFigures& gains, const ServoLoopModel& model);

// "gain margin 6.7 dB at 1.21 kHz, phase margin 37 deg at 212 Hz, |S| peak 2.1 at 260 Hz".
std::string describe_margins(const LoopMargins& m);

}  // namespace hystloop::ctl
