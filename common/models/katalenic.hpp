#pragma once
// Katalenic smooth parametric hysteresis model with shaping, in SI units:
//
//   y = psi_out( H(k1, k2)[ psi_in(u) ] ),    u [V] -> y [m]
//
// psi_in maps the voltage to "operator units" x, the bare operator (katalenic_operator.hpp) maps
// x to z in the same units, psi_out maps z to metres. k1 and k2 are therefore in operator units:
// k1 [x] is the half-width of the backlash band, k2 [1/x] the rate of the transition to its
// asymptotes. With the default linear psi_in of gain 1 the operator units are volts.
//
// KatalenicInverse runs v = H^{-1}(k1, k2)[z] between psi_out^{-1} and psi_in^{-1}: with equal
// parameters and initial conditions it is the exact left and right inverse (Prop. 4.1).
// Per-sample calls (forward, inverse, inverse_with_rates) are noexcept, allocation free and
// non-virtual; a non-finite input returns NaN and leaves the state untouched.

#include "models/katalenic_operator.hpp"
#include "models/katalenic_shaping.hpp"

namespace hystloop {

struct KatalenicParams {
  // Defaults: a piezo-like loop. With u = +-250 V periodic, the output swings 1.60 um and the
  // widest opening of the loop is 13 % of the stroke (tests/models/katalenic_test.cpp checks it).
  // The paper identifies no piezo (its examples are normalised), so these are chosen, not fitted.
  double k1 = 40.0;  // [operator units] = V with the default psi_in; |z - x| <= k1
  double k2 = 0.01;  // [1/operator unit]; at x = 0 when k2_slope != 0
  // Input-dependent k2 (Prop. 4.3): k2(x) = k2 + k2_slope * clamp(x, k2_domain_min, k2_domain_max).
  // The direct operator uses k2(x) of its input, the inverse k2(z) of its input (the paper's
  // approximate inverse; its error is bounded in katalenic_bounds.hpp).
  double k2_slope = 0.0;          // [1/operator unit^2]
  double k2_domain_min = -250.0;  // working interval L [operator units]
  double k2_domain_max = 250.0;
  // Initial condition: at reset the operator output is z0 = x0 + initial_offset (|.| <= k1);
  // 0 starts on the anhysteretic line z = x.
  double initial_offset = 0.0;                                             // [operator units]
  ShapingFunction input_shaping = ShapingFunction::make_linear(1.0);       // V -> operator units
  ShapingFunction output_shaping = ShapingFunction::make_linear(3.79e-9);  // operator units -> m

  // Throws ParameterError naming the field ("k1: must be > 0 (got -1)").
  void validate() const;

  double k2_at(double x) const noexcept;  // k2(x), the schedule of Prop. 4.3
  double k2_min() const noexcept;         // min of k2(x) over the working interval
  double k2_max() const noexcept;
  // Largest |dk2/dx| for which both operators stay strictly monotone: e * k2_min / (2 k1)
  // (M* <= 2 k1 and u~ e^{-k2 u~} <= 1/(e k2) in du~/dv~ = (1 - s k2' M* u~ e^{-k2 u~}) / (...)).
  double max_k2_slope() const noexcept;
};

class KatalenicModel {
 public:
  explicit KatalenicModel(const KatalenicParams& params);  // validates

  // Input u0 [V]; the operator output starts at psi_in(u0) + initial_offset.
  void reset(double u0 = 0.0) noexcept;
  double forward(double u) noexcept;  // u [V] -> y [m]

  const KatalenicParams& params() const noexcept { return params_; }
  // Validates, then re-anchors at the current input and output so the next forward() of the same
  // input returns the same output. If the output lies outside the new band |z - x| <= k1, it is
  // moved to the band's edge (the only case where the output jumps).
  void set_params(const KatalenicParams& params);

  double input() const noexcept { return u_; }                          // last u [V]
  double output() const noexcept { return y_; }                         // last y [m]
  const KatalenicDirectOperator& core() const noexcept { return op_; }  // operator-unit state

 private:
  KatalenicParams params_;
  KatalenicDirectOperator op_;
  double u_ = 0.0;
  double y_ = 0.0;
};

struct KatalenicRates {
  double u = 0.0;       // [V]
  double u_dot = 0.0;   // [V/s]
  double u_ddot = 0.0;  // [V/s^2]
};

class KatalenicInverse {
 public:
  explicit KatalenicInverse(const KatalenicParams& params);  // validates

  // Output y0 [m] the stage is at; the voltage starts at psi_in^{-1}(psi_out^{-1}(y0) - initial_offset),
  // the state KatalenicModel::reset reaches for the same y0.
  void reset(double y0 = 0.0) noexcept;
  double inverse(double y_ref) noexcept;  // y_ref [m] -> u [V]
  // inverse() plus its time derivatives from eqs. (7)-(8) through the shaping functions (chain
  // rule), for feedforward with input dynamics (Lemma 5.1). Rates take k2 as constant.
  KatalenicRates inverse_with_rates(double y_ref, double y_ref_dot, double y_ref_ddot) noexcept;

  const KatalenicParams& params() const noexcept { return params_; }
  // Validates, then re-anchors at the current reference and voltage (as KatalenicModel::set_params).
  void set_params(const KatalenicParams& params);

  double reference() const noexcept { return y_; }  // last y_ref [m]
  double output() const noexcept { return u_; }     // last u [V]
  const KatalenicInverseOperator& core() const noexcept { return op_; }

 private:
  KatalenicParams params_;
  KatalenicInverseOperator op_;
  double y_ = 0.0;
  double u_ = 0.0;
  double z_ = 0.0;  // last psi_out^{-1}(y_ref): warm start for a polynomial inverse
  double x_ = 0.0;  // last operator output
};

}  // namespace hystloop
