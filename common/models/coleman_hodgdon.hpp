#pragma once
// Coleman–Hodgdon differential model of hysteresis as used by Banning et al. (2001), eqs. (2), (3),
// (19), (20), u [V] -> w [m]:
//
//   dw/dt = -alpha |du/dt| (w - f(u)) + g(u) du/dt,
//   f(s) = a * clamp(s, -s_max, s_max),   g(s) = b for |s| <= s_max, 0 outside.
//
// The model is rate independent: on an input segment of constant direction sigma = sign(du),
//   dw/du = -sigma alpha (w - f(u)) + g(u),
// a linear ODE in u. f is piecewise linear and g piecewise constant, so each step is solved in
// CLOSED FORM (an exponential relaxation towards a particular solution on each of the three
// pieces, split at +-s_max): there is no integrator and no truncation error, only rounding.
// tests/models/coleman_hodgdon_test.cpp checks this against a fine RK4 reference.
//
// Between two samples the input is taken as monotone (a straight line from the previous input),
// which is exact for the bridge's zero-order-held voltage.
//
// Per-sample calls (step/forward) are noexcept, allocation free and non-virtual; a non-finite
// input returns NaN and leaves the state untouched.

namespace hystloop {

struct ColemanHodgdonParams {
  // Table 1 of the paper, converted to SI.
  double a = 8.58e-9;     // [m/V] slope of f: the loop centre moves along w = a u (Theorem 3)
  double b = 6.07e-9;     // [m/V] g inside +-s_max: the slope of small loops (Theorem 2)
  double alpha = 0.0123;  // [1/V] rate at which a branch relaxes onto f after a reversal
  // [V] saturation of f and g, eqs. (19)-(20). The paper gives no value and assumes the input stays
  // inside (-s_max, s_max); 750 V covers its actuator's range (-750 V, +250 V) and, with margin,
  // the bridge's +-250 V. Beyond +-s_max inequality (5) fails and branches may turn clockwise.
  double s_max = 750.0;

  // Throws ParameterError naming the field. Besides signs it enforces a/2 <= b <= a, the
  // paper's condition for (4)-(5) (b == a is allowed: the loop degenerates to the line w = a u).
  void validate() const;

  double f(double s) const noexcept;  // [m]
  double g(double s) const noexcept;  // [m/V]
};

class ColemanHodgdon {
 public:
  explicit ColemanHodgdon(const ColemanHodgdonParams& params = {});  // validates

  // Starts at input u0 [V] on the centre line w = f(u0) (the locus of loop centres, Theorem 3).
  void reset(double u0 = 0.0) noexcept;
  // Starts at input u0 [V] with output w0 [m].
  void reset(double u0, double w0) noexcept;

  // Moves the input from the previous value to u [V] and returns w [m]. No dt: rate independent.
  double step(double u) noexcept;
  double forward(double u) noexcept { return step(u); }  // the project's model interface

  // Validates, then keeps the current (u, w): the next step continues from there.
  void set_params(const ColemanHodgdonParams& params);
  const ColemanHodgdonParams& params() const noexcept { return params_; }

  double input() const noexcept { return u_; }   // last u [V]
  double output() const noexcept { return w_; }  // last w [m]

 private:
  // Exact solution across one piece of f/g, input moving monotonically from u0 to u1.
  double relax(double u0, double u1, double w0, double sigma) const noexcept;

  ColemanHodgdonParams params_;
  double u_ = 0.0;
  double w_ = 0.0;
};

}  // namespace hystloop
