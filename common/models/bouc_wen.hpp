#pragma once
// Bouc–Wen hysteresis (Bouc 1971; Wen 1976) in the form used for piezoelectric actuators by
// Low & Guo (1995, J. Microelectromech. Syst. 4(4)) and Rakotondrabe (2011, IEEE T-ASE 8(2)),
// u [V] -> y [m]:
//
//   y = d u - h,
//   dh/dt = alpha d du/dt - beta |du/dt| |h|^(n-1) h - gamma du/dt |h|^n.
//
// Units: u [V]; y, h [m]; d [m/V]; alpha, n [-]; beta, gamma [m^(1-n)/V] (1/V for n = 1), so
// that every term of dh/dt is in m/s.
//
// WHY this model: it is the plant most piezo papers simulate against, and its n = 1 case has a
// closed form, so a plant built on it is exact. It is also a different loop shape from the
// library's other models (the branch slope of y rises from d(1 - alpha) - (beta - gamma)|h| after a
// reversal towards d), which makes it a fair test plant for compensators identified on them.
//
// Stability: the parameters are restricted to Ikhouane, Mañosa & Rodellar (2007, Syst. Control
// Lett. 56, "Dynamic properties of the hysteretic Bouc–Wen model", Table 1, class I), the class
// that is bounded-input bounded-output for every initial state and the one their normalised form
//   h = h0 w,  dw/dt = rho (du/dt - sigma |du/dt||w|^(n-1) w + (sigma - 1) du/dt |w|^n),
//   h0 = (alpha d / (beta + gamma))^(1/n),  rho = alpha d / h0,  sigma = beta / (beta + gamma) >= 1/2
// describes: alpha d > 0, beta + gamma > 0, beta - gamma >= 0, n >= 1. In it
//   |h(t)| <= max(|h(0)|, h0)   for every input,
// since |h| grows only while sign(du) h >= 0 and |h|^n < alpha d / (beta + gamma), and shrinks
// when sign(du) h < 0. h_bound() is h0; tests/models/bouc_wen_test.cpp checks the bound.
//
// The model is rate independent: on an input segment of constant direction s = sign(du), with
// p = |u - u_start| the distance travelled,
//   dh/dp = s alpha d - beta |h|^(n-1) h - s gamma |h|^n.
// For n = 1 this is linear on each side of h = 0 and each step is solved in CLOSED FORM:
//   dh/dp = s alpha d - lambda h,  lambda = beta + gamma while s h >= 0, beta - gamma while s h < 0,
//   h(p) = h_inf + (h_start - h_inf) e^{-lambda p},  h_inf = s alpha d / lambda
// (h_start + s alpha d p when lambda = 0), split where h crosses 0 (at most once per segment:
// s h only increases on the lambda = beta - gamma side). Only rounding, no truncation error.
// For n != 1 each step is integrated with rk4_substeps classic RK4 sub-steps of equal length in
// u: the count is fixed, so the cost per sample is bounded; the truncation error is
// O((|du| / rk4_substeps)^4) per sample, so two sampling rates of the same path agree to that
// (not to rounding, as for n = 1). RK4 stays stable and monotone while each sub-step's
// |du| / rk4_substeps * n (beta + gamma) max(|h|, h0)^(n-1) stays below ~2.7.
//
// Between two samples the input is taken as monotone (a straight line from the previous input),
// which is exact for a zero-order-held voltage.
//
// Per-sample calls (step/forward) are noexcept, allocation free and non-virtual; a non-finite
// input returns NaN and leaves the state untouched.

namespace hystloop {

struct BoucWenParams {
  // Defaults: a piezo-like loop, chosen, not fitted (no paper gives SI values for a stack like
  // ours). With u = +-100 V periodic the output swings 10.8 um and the loop is 12.3 % of that
  // stroke wide at u = 0; the slope of y right after a reversal is 0.56 d, rising towards d
  // (tests/models/bouc_wen_test.cpp checks all three). How: d = 6.3e-8 m/V is a 100 V stack's
  // ~6 um per 100 V; alpha = 0.3 takes 30 % off the slope at a reversal (a piezo's small loops
  // are flatter than its major loop); beta + gamma = 0.02 /V makes a branch saturate over the
  // sweep (e^{-(beta + gamma) 2A} = e^{-4}), and with h_bound = alpha d / (beta + gamma) = 0.95 um
  // that sets the width; beta - gamma = 0.01 /V (gamma = beta / 3) keeps the turn at a reversal
  // gentle. For n = 1 the loop's shape depends only on alpha, beta A and gamma A, and d scales it:
  // d = 7.4e-9 m/V with beta = 0.006 /V, gamma = 0.002 /V gives the same 12.3 % loop over
  // +-250 V with the 3.17 um stroke of MemParams::paper_like().
  double d = 6.3e-8;      // [m/V] piezoelectric coefficient: the slope of y = d u - h without hysteresis
  double alpha = 0.3;     // [-] the hysteresis' share of the small-signal slope right after a reversal
  double beta = 0.015;    // [m^(1-n)/V] 1/V here (n = 1)
  double gamma = 0.005;   // [m^(1-n)/V]
  double n = 1.0;         // [-] >= 1; 1 is the piezo case and is solved in closed form
  int rk4_substeps = 16;  // [-] RK4 sub-steps per sample, used only when n != 1

  // Throws ParameterError naming the field: d, alpha > 0; beta > 0; -beta < gamma <= beta (i.e.
  // beta + gamma > 0 and beta - gamma >= 0, class I above); n finite and >= 1; rk4_substeps in
  // [1, 4096]. All finite.
  void validate() const;

  // (alpha d / (beta + gamma))^(1/n) [m]: |h| never grows beyond max(|h(0)|, h_bound()).
  double h_bound() const noexcept;
};

// u [V] -> y [m].
class BoucWen {
 public:
  explicit BoucWen(const BoucWenParams& params = {});  // validates

  // Starts at input u0 [V] with h = 0: demagnetised, y = d u0 (a non-finite u0 is taken as 0).
  void reset(double u0 = 0.0) noexcept;
  // Starts at input u0 [V] with the hysteretic state h0 [m] (y = d u0 - h0).
  void reset(double u0, double h0) noexcept;

  // Moves the input from the previous value to u [V] and returns y [m]. No dt: rate independent.
  double step(double u) noexcept;
  double forward(double u) noexcept { return step(u); }  // the project's model interface

  // Validates, then keeps the current (u, h): the next step continues from there (y jumps by
  // (d_new - d_old) u when d changes).
  void set_params(const BoucWenParams& params);
  const BoucWenParams& params() const noexcept { return params_; }

  double input() const noexcept { return u_; }                    // last u [V]
  double output() const noexcept { return params_.d * u_ - h_; }  // last y [m]
  double hysteretic_state() const noexcept { return h_; }         // last h [m]

 private:
  double step_exact(double u) const noexcept;  // n == 1: the closed form, from (u_, h_) to u
  double step_rk4(double u) const noexcept;    // n != 1

  BoucWenParams params_;
  double u_ = 0.0;
  double h_ = 0.0;
};

}  // namespace hystloop
