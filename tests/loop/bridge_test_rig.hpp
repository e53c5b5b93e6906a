#pragma once
// A BridgeCore on a first-order plant, ticked by the test: what bridge_core_test and
// bridge_servo_test drive. Commands are submitted just in time unless a test says otherwise.

#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "loop/bridge_core.hpp"

namespace hystloop::testing {

inline constexpr double kDt = 1e-4;
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr double kGain = 1e-8;  // plant and servo: 1 um per 100 V

inline CommandTick command(std::int64_t seq, double u_ff_V, double y_ref_m = kNaN, std::int32_t version = 1) {
  return {seq, u_ff_V, y_ref_m, version, 2};
}

inline FeedbackGains servo_gains(double kp, double ki) {
  FeedbackGains g;
  g.kp = kp;
  g.ki = ki;
  g.nominal_gain_m_per_V = kGain;
  return g;
}

// y' = (gain u + d - y) / tau, discretised exactly over a tick (u held).
struct FirstOrderPlant {
  double gain_m_per_V = kGain;
  double disturbance_m = 20e-9;
  double tau_s = 1e-3;
  double y_m = 0.0;
  double step(double u_V) {
    y_m += (1.0 - std::exp(-kDt / tau_s)) * (gain_m_per_V * u_V + disturbance_m - y_m);
    return y_m;
  }
};

struct BridgeRig {
  explicit BridgeRig(const ActuatorLimits& limits = {}, const FeedbackGains& gains = {})
      : bridge(std::make_unique<BridgeCore>(limits, gains, kDt)) {  // 256 kB of buffer: off the stack
    bridge->arm(0);
  }

  // Tick k = next_k: submits (seq k, u_ff, y_ref) just in time, ticks with the position measured at
  // the end of the previous tick, steps the plant.
  BridgeTick step(double u_ff_V, double y_ref_m) {
    bridge->submit(command(k, u_ff_V, y_ref_m));
    return step_without_command();
  }
  BridgeTick step_without_command() {
    const BridgeTick t = bridge->tick(k++, plant.y_m);
    plant.step(t.u_applied_V);
    return t;
  }

  std::unique_ptr<BridgeCore> bridge;
  FirstOrderPlant plant;
  std::int64_t k = 0;
};

}  // namespace hystloop::testing
