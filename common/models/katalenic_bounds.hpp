#pragma once
// Error bounds of the Katalenic operator under parameter mismatch (paper §3 and Prop. 4.3), in
// operator units unless an output shaping function converts them.
//
// The family RH(k1, dk1, k2, dk2) of Definition 2.8 holds every H(k1*, k2*) with
// |k1* - k1| <= dk1 and |k2* - k2| <= dk2. Using H^{-1}(k1, k2) for a plant that is any member:
//   Prop. 3.2 (12): |H^{-1}(k1*, k2*)[u_d] - H^{-1}(k1, k2)[u_d]| <= Delta_a
//   Prop. 3.3 (15): |H(k1*, k2*)[H^{-1}(k1, k2)[u_d]] - u_d|     <= Delta_b <= Delta_a
// where Delta_a is the largest |Delta_x| of (14) over the four corners (13) of the family.

#include "models/katalenic.hpp"
#include "models/katalenic_shaping.hpp"

namespace hystloop {

// RH(k1, dk1, k2, dk2), Definition 2.8 (operator units; k2 in 1/operator unit).
struct KatalenicFamily {
  double k1 = 0.0;
  double dk1 = 0.0;
  double k2 = 0.0;
  double dk2 = 0.0;
  // Throws ParameterError unless k1, k2 > 0, 0 <= dk1 < k1, 0 <= dk2 < k2 (every member valid).
  void validate() const;
};

// (14): Delta_x*(x) = k1_bar - k1 + 2 (k1 e^{-k2 x} - k1_bar e^{-k2_bar x}).
double katalenic_error_envelope(double k1, double k1_bar, double k2, double k2_bar, double x) noexcept;
// (13): x = max(ln(k1_bar k2_bar / (k1 k2)) / (k2_bar - k2), 0), the extremum of (14); 0 when none.
double katalenic_error_extremum(double k1, double k1_bar, double k2, double k2_bar) noexcept;
// sup over x >= 0 of |Delta_x*(x)| for one estimated pair: the larger of |k1_bar - k1| (both
// ends of (14)) and |Delta_x*| at the extremum.
double katalenic_error_peak(double k1, double k1_bar, double k2, double k2_bar) noexcept;

// (12): Delta_a over the corners k1_bar in {k1_bar_lo, k1_bar_hi}, k2_bar in {k2_bar_lo, k2_bar_hi}.
// (14) is affine in k1_bar and monotone in k2_bar at every x, so the corners hold the supremum.
double katalenic_inverse_error_bound(double k1, double k2, double k1_bar_lo, double k1_bar_hi, double k2_bar_lo,
                                     double k2_bar_hi) noexcept;
double katalenic_inverse_error_bound(const KatalenicFamily& family);  // validates the family

// (15): |Delta_b| <= |Delta_a|, in operator units ...
double katalenic_compensation_error_bound(const KatalenicFamily& family);
// ... and in output units, through the output shaping's largest slope (the paper's Example 1:
// 0.13 x 1.4 = 0.182).
double katalenic_compensation_error_bound(const KatalenicFamily& family, const ShapingFunction& output_shaping);

// Prop. 4.3: with k2 = phi(x) the approximate inverse H^{-1}(k1, phi(u_d)) sees a k2 mismatch
// of at most sup |phi'| k1 (because |v - u_d| <= k1).
double katalenic_k2_deviation(const KatalenicParams& params) noexcept;
// Prop. 4.3 combined with (12)/(15): the largest Delta_a over nominal k2 in [k2_min, k2_max] of
// the schedule, with k2_bar within the deviation but inside [k2_min, k2_max] (k2 never leaves
// the schedule's range) and k1_bar within k1 +- dk1. Operator units.
double katalenic_input_dependent_k2_bound(const KatalenicParams& params, double dk1 = 0.0) noexcept;

}  // namespace hystloop
