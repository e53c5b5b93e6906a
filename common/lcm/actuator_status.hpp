#pragma once
// The actuator limits in force, as the bridge reports them on HX_STATUS: the rig's one set, which
// the compensator and the re-identifier compare their own with at run time (runtime/rig_check.hpp).
// service_status_t's counters are integers >= 0, so each limit travels in mV (mV/s), the voltages
// counted from -10 kV, the lowest any config accepts: "actuator_u_min_mV_from_-10kV" is
// round((u_min_V + 1e4) x 1e3). Axis x's under these names, the others' behind their axis
// ("y_actuator_u_max_mV_from_-10kV"), as the servo's gains (lcm/servo_gains_status.hpp).

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "lcm/status_counters.hpp"

namespace hystloop {

struct ActuatorFigures {
  double u_min_V = 0.0;       // [V]
  double u_max_V = 0.0;       // [V]
  double slew_V_per_s = 0.0;  // [V/s]
};

struct ActuatorCounter {
  std::string_view name;
  std::string_view key;  // the config key it reports (actuator.<key>)
  double origin;         // counter = round((value - origin) x 1e3)
  double ActuatorFigures::*value;
};

inline constexpr double kActuatorVoltageOrigin_V = -1e4;

inline constexpr std::array<ActuatorCounter, 3> kActuatorCounters{{
    {"actuator_u_min_mV_from_-10kV", "u_min_V", kActuatorVoltageOrigin_V, &ActuatorFigures::u_min_V},
    {"actuator_u_max_mV_from_-10kV", "u_max_V", kActuatorVoltageOrigin_V, &ActuatorFigures::u_max_V},
    {"actuator_slew_mV_per_s", "slew_V_per_s", 0.0, &ActuatorFigures::slew_V_per_s},
}};

// The counter value of one limit (0 for a value below its origin, which no config accepts).
inline std::uint64_t actuator_counter(const ActuatorCounter& c, const ActuatorFigures& a) noexcept {
  const double v = (a.*c.value - c.origin) * 1e3;
  return v > 0.0 && std::isfinite(v) ? static_cast<std::uint64_t>(std::llround(v)) : 0U;
}

// The limit a counter value stands for.
inline double actuator_value(const ActuatorCounter& c, std::int64_t counter) noexcept {
  return static_cast<double>(counter) * 1e-3 + c.origin;
}

// The stage's nominal gain the bridge's servo is scaled by (servo.nominal_gain_m_per_V), in fm/V
// (6.3e-9 m/V is 6,300,000): the one gain every process of a rig judges a stage's models against.
inline constexpr std::string_view kNominalGainCounter = "servo_nominal_gain_fm_per_V";
inline constexpr double kNominalGainScale = 1e15;

inline std::uint64_t nominal_gain_counter(double gain_m_per_V) noexcept {
  const double v = gain_m_per_V * kNominalGainScale;
  return v > 0.0 && std::isfinite(v) ? static_cast<std::uint64_t>(std::llround(v)) : 0U;
}

// Axis `axis`'s counter name: c.name for x (0), "y_" + c.name, "z_" + c.name.
inline std::string actuator_counter_name(const ActuatorCounter& c, int axis) { return axis_counter_name(c.name, axis); }

}  // namespace hystloop
