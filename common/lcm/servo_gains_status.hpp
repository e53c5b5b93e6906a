#pragma once
// The servo's gains in force, as the bridge reports them on HX_STATUS and hystloop-ctl reads them
// back. service_status_t carries integers only, so each gain travels as a counter in a fixed
// fraction of its SI unit, named with that unit: "servo_kp_ppm" is kp x 1e6. The resolution
// (1e-6 of kp, 1 ps of kd, 1 mHz of the notch) is far below anything a gain change is made with;
// a partial change is merged by the bridge from the exact values, never from these. A stage of
// several axes reports axis x's under these names and the others' behind their axis ("y_servo_kp_ppm").

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "lcm/status_counters.hpp"

namespace hystloop {

struct ServoGainsFigures {
  double kp = 0.0;         // [-]
  double ki_per_s = 0.0;   // [1/s]
  double kd_s = 0.0;       // [s]
  double notch_hz = 0.0;   // [Hz], 0 = no notch
  double notch_q = 0.0;    // [-]
  double notch2_hz = 0.0;  // [Hz], the second notch; 0 = none
  double notch2_q = 0.0;   // [-]
};

struct ServoGainCounter {
  std::string_view name;
  double scale;  // counter = round(value x scale)
  double ServoGainsFigures::*value;
  bool required = true;  // false: a bridge that does not report it has none (0)
};

inline constexpr std::array<ServoGainCounter, 7> kServoGainCounters{{
    {"servo_kp_ppm", 1e6, &ServoGainsFigures::kp},
    {"servo_ki_ppm_per_s", 1e6, &ServoGainsFigures::ki_per_s},
    {"servo_kd_ps", 1e12, &ServoGainsFigures::kd_s},
    {"servo_notch_mHz", 1e3, &ServoGainsFigures::notch_hz},
    {"servo_notch_q_ppm", 1e6, &ServoGainsFigures::notch_q},
    // A bridge built before the second notch reports none: it has none.
    {"servo_notch2_mHz", 1e3, &ServoGainsFigures::notch2_hz, false},
    {"servo_notch2_q_ppm", 1e6, &ServoGainsFigures::notch2_q, false},
}};

// The counter value of one gain (gains are >= 0 and bounded, so this fits).
inline std::uint64_t servo_gain_counter(const ServoGainCounter& c, const ServoGainsFigures& g) noexcept {
  const double v = g.*c.value * c.scale;
  return v > 0.0 && std::isfinite(v) ? static_cast<std::uint64_t>(std::llround(v)) : 0U;
}

// Axis `axis`'s counter name: c.name for x (0), "y_" + c.name, "z_" + c.name.
inline std::string servo_gain_counter_name(const ServoGainCounter& c, int axis) {
  return axis_counter_name(c.name, axis);
}

// Axis `axis`'s gains from a report's counters; nullopt when a required one is missing (a bridge
// that reports none, or not that axis).
template <class FindCounter>
std::optional<ServoGainsFigures> servo_gains_from_counters(FindCounter&& find, int axis = 0) {
  ServoGainsFigures g;
  for (const ServoGainCounter& c : kServoGainCounters) {
    const std::optional<std::int64_t> v = find(servo_gain_counter_name(c, axis));
    if (!v && c.required) return std::nullopt;
    g.*c.value = v ? static_cast<double>(*v) / c.scale : 0.0;
  }
  return g;
}

}  // namespace hystloop
