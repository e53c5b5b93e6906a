#pragma once
// The bare parametric hysteresis operator pair of Katalenic, van Lierop & van den Bosch,
// "Smooth Parametric Hysteresis Operator for Control" (docs/REFERENCES.md [3]), in
// operator units (no shaping; katalenic.hpp adds shaping and SI units).
//
//   direct  (2):  u~ = v~ - M* + W(k2 M* e^{k2 (M* - v~)}) / k2,  M* = M(v, u) + k1
//   inverse (4):  v~ = u_d~ + M* (1 - e^{-k2 u_d~}),            M* = -M(u_d, v) + k1
//
// with the transformation T and the function M of Definition 2.1 (ReversalMemory below).
// Ascending, the direct operator tends to u = v - k1, descending to u = v + k1 (Remark 2.3).
// Everything here is noexcept and allocation free: it is the per-sample path.

namespace hystloop {

// Principal-branch Lambert W through Boost.Math (lambert_w0) with a policy that never throws;
// z must be >= -1/e (here it is always >= 0).
double lambert_w0_nothrow(double z) noexcept;

// W0(e^s) for any finite s. For s >= kLogDomainThreshold e^s would overflow (or lose the
// argument's precision), so it solves w + ln w = s by Newton from the asymptotic w ~ s - ln s.
double lambert_w0_of_exp(double s) noexcept;
inline constexpr double kLogDomainThreshold = 690.0;

// Eq. (2) on one branch: u~ from v~ >= 0 and M* in [0, 2 k1].
double katalenic_direct_branch(double k2, double m_star, double v_tilde) noexcept;
// Eq. (4) on one branch: v~ from u_d~ >= 0 and M* in [0, 2 k1].
double katalenic_inverse_branch(double k2, double m_star, double ud_tilde) noexcept;

// Definition 2.1: (alpha0, beta0) are input and output at the last reversal of the input.
// In discrete time the reversal point is the previous sample (the extremum), latched when the
// sign of the input step changes. A zero step keeps the direction: the paper's alpha_dot >= 0
// would re-latch at every hold of a falling input, which changes nothing (the operator is a
// Duhem model: its branch through a point does not depend on where it was latched) but costs
// rounding.
class ReversalMemory {
 public:
  void reset(double alpha, double beta, double direction = 1.0) noexcept {
    alpha0_ = last_alpha_ = alpha;
    beta0_ = last_beta_ = beta;
    direction_ = direction < 0.0 ? -1.0 : 1.0;
  }
  // Call with the new input before computing the output.
  void advance(double alpha) noexcept {
    const double step = alpha - last_alpha_;
    if ((step > 0.0 && direction_ < 0.0) || (step < 0.0 && direction_ > 0.0)) {
      alpha0_ = last_alpha_;
      beta0_ = last_beta_;
      direction_ = -direction_;
    }
  }
  void commit(double alpha, double beta) noexcept {
    last_alpha_ = alpha;
    last_beta_ = beta;
  }
  double alpha_tilde(double alpha) const noexcept { return direction_ * (alpha - alpha0_); }  // T, first part
  double beta_from_tilde(double beta_tilde) const noexcept { return beta0_ + direction_ * beta_tilde; }
  double m() const noexcept { return direction_ * (beta0_ - alpha0_); }  // M(alpha, beta)
  double direction() const noexcept { return direction_; }               // +1 ascending, -1 descending
  double last_alpha() const noexcept { return last_alpha_; }
  double last_beta() const noexcept { return last_beta_; }
  double alpha0() const noexcept { return alpha0_; }
  double beta0() const noexcept { return beta0_; }

 private:
  double alpha0_ = 0.0, beta0_ = 0.0, last_alpha_ = 0.0, last_beta_ = 0.0, direction_ = 1.0;
};

// u = H(k1, k2)[v]. k2 is passed per call so that it may depend on the input (Prop. 4.3).
class KatalenicDirectOperator {
 public:
  // Starts at input v0 and output u0; |u0 - v0| <= k1 keeps the state inside the loop.
  void reset(double v0, double u0, double direction = 1.0) noexcept { memory_.reset(v0, u0, direction); }
  double apply(double v, double k1, double k2) noexcept;
  const ReversalMemory& memory() const noexcept { return memory_; }

 private:
  ReversalMemory memory_;
};

struct OperatorRates {
  double value = 0.0;         // v
  double rate = 0.0;          // dv/dt, eq. (7)
  double acceleration = 0.0;  // d2v/dt2, eq. (8)
};

// v = H^{-1}(k1, k2)[u_d].
class KatalenicInverseOperator {
 public:
  // Starts at input u_d0 and output v0.
  void reset(double ud0, double v0, double direction = 1.0) noexcept { memory_.reset(ud0, v0, direction); }
  double apply(double ud, double k1, double k2) noexcept;
  // apply() plus the time derivatives of Proposition 2.7 for constant k2. The paper prints (8)
  // with -M* k2^2 e^{-k2 u_d~} u_d_dot^2, which is the ascending branch; differentiating (4) on a
  // descending branch flips that sign, so the term is written with u_d_dot * |u_d_dot| here.
  OperatorRates apply_with_rates(double ud, double ud_dot, double ud_ddot, double k1, double k2) noexcept;
  const ReversalMemory& memory() const noexcept { return memory_; }

 private:
  ReversalMemory memory_;
};

}  // namespace hystloop
