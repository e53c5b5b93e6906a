#pragma once
// Closed forms of Banning et al. (2001) for the stationary loop of the Coleman–Hodgdon model
// (Theorem 3, eqs. (21)-(24)) under u = u_offset + A sin(wt) with |u_offset| + A <= s_max, and the
// magnitude response of the second-order stage (the quantity (27) estimates).
//
// Three flavours of each loop feature:
//   theorem3_features()         the paper's left-hand closed forms. All are exact except delta,
//                               which the paper derives with 1 - e^{-alpha delta / 2} ~ alpha delta / 2;
//   theorem3_small_amplitude()  the paper's right-hand approximations for alpha A << 1;
//   exact_loop_features()       delta solved exactly (root of the closed-form branch), the others
//                               as in theorem3_features(). This is the truth for the tests.
// Out of the domain (A <= 0 or beyond s_max) every value is NaN.

#include "models/coleman_hodgdon.hpp"
#include "models/loop_features.hpp"
#include "models/second_order_stage.hpp"

namespace hystloop {

// Turning points y^{down,up} at u_offset - A and y^{up,down} at u_offset + A (proof of Theorem 3).
double ch_left_turning_point(const ColemanHodgdonParams& p, double u_offset, double amplitude) noexcept;
double ch_right_turning_point(const ColemanHodgdonParams& p, double u_offset, double amplitude) noexcept;

double ch_slope(const ColemanHodgdonParams& p, double amplitude) noexcept;                      // (21) [m/V]
double ch_horizontal_aperture(const ColemanHodgdonParams& p, double amplitude) noexcept;        // (22) [V]
double ch_horizontal_aperture_exact(const ColemanHodgdonParams& p, double amplitude) noexcept;  // [V]
double ch_vertical_aperture(const ColemanHodgdonParams& p, double amplitude) noexcept;          // (23) [m]
double ch_area(const ColemanHodgdonParams& p, double amplitude) noexcept;                       // (24) [m V]

double ch_slope_small(const ColemanHodgdonParams& p) noexcept;                                  // b
double ch_horizontal_aperture_small(const ColemanHodgdonParams& p, double amplitude) noexcept;  // alpha (a/b - 1) A^2
double ch_vertical_aperture_small(const ColemanHodgdonParams& p, double amplitude) noexcept;    // alpha (a - b) A^2
double ch_area_small(const ColemanHodgdonParams& p, double amplitude) noexcept;                 // 4/3 (a - b) alpha A^3

LoopFeatures theorem3_features(const ColemanHodgdonParams& p, double u_offset, double amplitude) noexcept;
LoopFeatures theorem3_small_amplitude(const ColemanHodgdonParams& p, double u_offset, double amplitude) noexcept;
LoopFeatures exact_loop_features(const ColemanHodgdonParams& p, double u_offset, double amplitude) noexcept;

// |G(jw)| of (28)-(29): k / sqrt((k - w^2)^2 + (c w)^2), omega [rad/s].
double stage_magnitude(const SecondOrderStageParams& p, double omega) noexcept;
// (25): stationary y_max - y_min [m] of the paper's order (stage first) for input amplitude A [V]
// when the stage's magnitude at the drive frequency is h.
double banning_peak_to_peak(const ColemanHodgdonParams& p, double magnitude, double amplitude) noexcept;
// (27): the estimate h = (y_max - y_min) / (2 b A) that inverts (25) under alpha A h << 1.
double magnitude_from_peak_to_peak(double peak_to_peak, double b, double amplitude) noexcept;

}  // namespace hystloop
