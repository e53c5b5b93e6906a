#pragma once
// What a reference asks of the actuator, in closed form, for a linear plant: the voltage range and
// rate the feedforward needs to make the stage follow a sine or a rounded triangle, and the inverse
// questions (the largest amplitude at a frequency, the highest frequency at an amplitude, the
// shortest corner of a triangle) for given limits.
//
// The plant is a static gain g [m/V], optionally followed by Banning's stage
// y'' + c y' + k y = k w (unit DC gain), inverted exactly in continuous time: the feedforward is
//   u = (y + (c/k) y' + y''/k) / g.
// For a linear plant the order of gain and stage does not matter. These are a fast first answer
// and what the tests check against; a hysteresis inverse needs a dry run of that inverse instead
// (its local slope is not g), and the discrete inverse at the tick differs from the continuous one
// near half the tick rate. The approach from the previous reference (blend_s) is not covered.
//
// Sine y = A sin(w t) + offset, w = 2 pi f:
//   u in offset/g +- |A| M(w) / g,   |du/dt| <= w |A| M(w) / g,   M(w) = |k - w^2 + i c w| / k
//   (M = 1 without the stage).
// Rounded triangle (trajectory.hpp: slope v on the straight parts, corners of tau [s]): exact peaks
// over the whole period,
//   |du/dt| = (v/g) max(1, hypot(pi^2/(k tau^2) - 1, c pi/(k tau)))
//             <= (v/g) (1 + (c/k) pi/tau + pi^2/(k tau^2)),
//   u in offset/g +- W/g,  W = |A| - v tau/pi + (a >= 0 ? hypot(a, b) : b),
//   a = v (tau/pi - pi/(k tau)),  b = c v / k,
// from the corner's y = A - (v tau/pi)(1 - cos th), y' = -v sin th, th in [-pi/2, pi/2]; without the
// stage simply |du/dt| = v/g and W = |A|. A sharp corner (tau = 0) with the stage needs an
// unbounded voltage and rate.

#include <cstdint>
#include <optional>

#include "loop/trajectory.hpp"
#include "models/second_order_stage.hpp"

namespace hystloop {

struct LinearPlant {
  double gain_m_per_V = 0.0;                    // g > 0: position per volt
  std::optional<SecondOrderStageParams> stage;  // Banning's stage in series; none = static gain only

  // Throws ParameterError: "plant.gain_m_per_V", "plant.stage.k", "plant.stage.c".
  void validate() const;
};

// The actuator's limits (as the bridge's ActuatorLimits) and the fraction of them the feedforward
// may use (the rest is the servo's and the model error's): the range shrunk about its centre, and
// the slew limit, both by `fraction`.
struct FeedforwardLimits {
  double u_min_V = -250.0;
  double u_max_V = 250.0;
  double slew_V_per_s = 5.0e4;
  double fraction = 1.0;  // (0, 1]

  // Throws ParameterError: "limits.u_min_V", "limits.u_max_V" (above u_min_V), "limits.slew_V_per_s",
  // "limits.fraction".
  void validate() const;
  double usable_min_V() const noexcept;
  double usable_max_V() const noexcept;
  double usable_slew_V_per_s() const noexcept;
};

// The voltage a reference needs: its lowest and highest value and its peak rate (magnitude).
struct VoltageNeed {
  double u_min_V = 0.0;
  double u_max_V = 0.0;
  double rate_V_per_s = 0.0;
};

enum class Limit : std::int8_t { kNone = 0, kRange = 1, kSlew = 2 };

// "none", "range", "slew".
const char* to_string(Limit limit) noexcept;

// The first limit (range, then slew) the need breaks of what the feedforward may use; kNone when
// it fits (the limits themselves included).
Limit exceeded_limit(const VoltageNeed& need, const FeedforwardLimits& limits) noexcept;
inline bool fits(const VoltageNeed& need, const FeedforwardLimits& limits) noexcept {
  return exceeded_limit(need, limits) == Limit::kNone;
}

// M(f) = |k - w^2 + i c w| / k, the stage inverse's gain at f [Hz]; 1 without the stage.
double stage_inverse_gain(const LinearPlant& plant, double frequency_hz) noexcept;

// The closed forms above. Throw ParameterError for an invalid plant or reference ("frequency_hz",
// "corner_s": >= 0 and below half the period).
VoltageNeed sine_need(const LinearPlant& plant, double amplitude_m, double frequency_hz, double offset_m);
VoltageNeed triangle_need(const LinearPlant& plant, double amplitude_m, double frequency_hz, double corner_s,
                          double offset_m);

// Any spec: sine and cosine (phase does not matter), triangle (its corner_s as given: 0 is a sharp
// corner here), hold (the offset, rate 0) and points (their lowest and highest point, the
// steepest segment's slope; with the stage, unbounded at any kink). Validates the spec.
VoltageNeed voltage_need(const LinearPlant& plant, const TrajectorySpec& spec);

// The largest |amplitude| [m] of a sine at f around offset_m that fits; 0 when the offset alone
// does not.
double largest_sine_amplitude_m(const LinearPlant& plant, const FeedforwardLimits& limits, double frequency_hz,
                                double offset_m);

// The highest f [Hz] such that a sine of this amplitude around offset_m fits at every frequency in
// (0, f] (near the stage's resonance M(f) dips and a higher band may fit again: it is not
// reported); 0 when not even a slow sine fits the range, +inf for amplitude 0 at a fitting offset.
// With the stage, the roots of a cubic (rate) and a quadratic (range) in w^2, to rounding.
double highest_sine_frequency_hz(const LinearPlant& plant, const FeedforwardLimits& limits, double amplitude_m,
                                 double offset_m);

// The largest |amplitude| [m] of a triangle at f with corners of corner_s around offset_m that fits
// (the need is proportional to it); 0 when the offset alone does not fit or a sharp corner meets
// the stage.
double largest_triangle_amplitude_m(const LinearPlant& plant, const FeedforwardLimits& limits, double frequency_hz,
                                    double corner_s, double offset_m);

// The shortest corner [s] in [0, T/2) with which the triangle fits; nullopt when none does.
// Without the stage the need grows with the corner, so this is 0 or nothing. With it, searched on a
// log grid (300 points per decade, from 1e-9 of half the period) and refined by bisection to
// rounding: the result always fits; a window of fitting corners narrower than 0.8 % of the corner,
// below the first one found, would be missed.
std::optional<double> shortest_triangle_corner_s(const LinearPlant& plant, const FeedforwardLimits& limits,
                                                 double amplitude_m, double frequency_hz, double offset_m);

}  // namespace hystloop
