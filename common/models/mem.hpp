#pragma once
// Memory-element (MEM) hysteresis model of Strijbosch, Tiels & Oomen: the Ramberg–Osgood model
// (2)–(3) written, by Theorem 4, as a hybrid MEM element whose slope depends only on the distance
// p = |u - u_i| travelled since the last branching point (u_i, y_i):
//
//   dy/du = M(p) = c1 + c2 p^c3                                                   (6), (7)
//
// Integrated in closed form along a branch (no Euler accumulation anywhere):
//
//   y - y_i = sign(u - u_i) F(|u - u_i|),   F(p) = c1 p + c2 p^(c3+1) / (c3+1)    (= (3))
//
// and, from (2), the skeleton (virgin curve through the origin) is the same curve at half scale,
// the Masing relation (its slope is c1 + c2 (2|u|)^c3 = M(2|u|)):
//
//   y = sign(u) F(2|u|) / 2                                                      (= (2))
//
// The model remembers only the latest branching point, as the paper's model does: a minor loop
// that closes is NOT wiped out (no Masing memory); the input simply follows the branch that started
// at its last reversal, wherever that leads.
//
// MemInverse is the feedforward of Theorem 10, (21)–(23): F is strictly increasing, so u reverses
// exactly when y_ref does; each branch equation is solved exactly for p (Newton on the convex F,
// always from above), so MemModel(MemInverse(y_ref)) == y_ref to rounding, with nothing to drift.
//
// Per-sample calls are noexcept, allocation free and non-virtual; a non-finite input returns NaN
// and leaves the state untouched.

#include <cstdint>

#include "models/reversal_detector.hpp"

namespace hystloop {

struct MemParams {
  // Defaults = paper_like(). The paper reports its identified mapping only as a plot (Fig. 7), no
  // numbers, so these are chosen to reproduce the scale of its experiment instead: a +-250 V major
  // loop spans 3.17 um (the reference (24) is +-1.6 um) and is 11.9 % of that stroke wide at u = 0;
  // the slope grows from c1 at a reversal to 1.59 c1 at the far end of the major loop.
  double c1 = 5.0e-9;   // [m/V] slope right after a reversal, M(0)
  double c2 = 1.7e-12;  // [m/V^(1+c3)] growth of the slope with p
  double c3 = 1.2;      // [-] exponent of that growth (gamma - 1 of Ramberg–Osgood)

  static MemParams paper_like() noexcept { return {}; }

  // Throws ParameterError naming the field. The domain is the paper's (Theorem 4) and is what the
  // inverse needs: c1 > 0 (y*, u* > 0; it also makes F strictly increasing, hence invertible, with
  // M >= c1 > 0 everywhere), c2 >= 0 (alpha >= 0; c2 = 0 is a linear spring), c3 > 0 (gamma > 1;
  // makes M continuous at a reversal, M(0) = c1, and F convex). All finite.
  void validate() const;

  double slope(double p) const noexcept;          // M(p) [m/V], p >= 0 [V]
  double branch_rise(double p) const noexcept;    // F(p) [m], p >= 0 [V]
  double branch_run(double rise) const noexcept;  // F^-1(rise) [V], rise >= 0 [m] (cold solve)
  double skeleton(double u) const noexcept;       // y on the skeleton (2) [m] at u [V]
};

// Ramberg–Osgood parameters of (2)–(3).
struct RambergOsgoodParams {
  double y_star = 0.0;  // [m]
  double u_star = 0.0;  // [V]
  double alpha = 0.0;   // [-] >= 0
  double gamma = 2.0;   // [-] > 1

  void validate() const;  // the paper's domain: y*, u* > 0, alpha >= 0, gamma > 1

  // Theorem 4: c1 = y*/u*, c2 = (y*/u*) alpha gamma / (2u*)^(gamma-1), c3 = gamma - 1.
  // (Theorem 10 restates c2 without the factor y*/u*; the proof of Theorem 4 has it, and (3)
  // differentiated confirms it: tests/models/mem_test.cpp checks both curves against (2)/(3).)
  MemParams to_mem() const;
  // The converse is not unique ((y*, u*, alpha) scale together): u* [V] is chosen by the caller.
  static RambergOsgoodParams from_mem(const MemParams& mem, double u_star);

  double skeleton(double u) const noexcept;                        // (2) [m]
  double branch(double u, double u_i, double y_i) const noexcept;  // (3) [m]
};

// What the model and its inverse share, so that they agree branch for branch: the parameters,
// and the branch they are on, which starts at (u_origin_, y_origin_) and is the skeleton until the
// first reversal.
class MemBranchState {
 public:
  const MemParams& params() const noexcept { return params_; }
  double branch_origin_u() const noexcept { return u_origin_; }  // [V]
  bool on_skeleton() const noexcept { return scale_ != 1.0; }
  std::uint64_t reversals() const noexcept { return reversals_; }  // since construction/reset

 protected:
  MemBranchState(const MemParams& params, double reversal_deadband);  // validates both
  // Onto the skeleton (scale 2, origin (0, 0)) or a branch (scale 1), counting no reversal.
  void restart(double u_origin, double y_origin, double scale) noexcept;
  void reverse_at(double u, double y) noexcept;  // a reversal at (u, y): the branch from there

  MemParams params_;
  double u_origin_ = 0.0;
  double y_origin_ = 0.0;
  double scale_ = 2.0;  // 2 on the skeleton (Masing: half-scale branch about the origin), 1 on a branch
  std::uint64_t reversals_ = 0;
};

// u [V] -> y [m].
class MemModel : public MemBranchState {
 public:
  // reversal_deadband [V] >= 0, see ReversalDetector; 0 (default) is the paper's model.
  explicit MemModel(const MemParams& params = {}, double reversal_deadband = 0.0);

  // Virgin state at u0, on the skeleton (2), as if loaded monotonically from 0 to u0.
  void reset(double u0 = 0.0) noexcept;
  // State right after a branching point at (u_origin [V], y_origin [m]); the next move sets the
  // direction without counting a reversal. This is Theorem 10's "after its first branching point".
  void reset_to_branch(double u_origin, double y_origin) noexcept;

  double forward(double u) noexcept;

  // Validates, then keeps the branch origin's input and the current (u, y), shifting the origin's
  // output so the new curve passes through (u, y): no jump. At a reversal (p = 0) this is a pure
  // slope change.
  void set_params(const MemParams& params);

  double input() const noexcept { return u_; }   // last u [V]
  double output() const noexcept { return y_; }  // last y [m]
  int direction() const noexcept { return detector_.direction(); }

 private:
  double curve(double u) const noexcept;  // y on the current branch (or skeleton) at u

  ReversalDetector detector_;
  double u_ = 0.0;
  double y_ = 0.0;
  double y_extremum_ = 0.0;  // y at detector_.extremum(): the next branching point's output
};

// y_ref [m] -> u [V]: the exact feedforward of Theorem 10.
//
// Branching is decided on the u it emits, exactly as MemModel will see that u: y_ref turning
// starts a new branch at the last (u, y) only if the new u actually moves back; a turn too small to
// move u (rounding) is answered by holding u. So the model driven by this u has the same branch
// origins, sample for sample, and MemModel(MemInverse(y_ref)) == y_ref to rounding.
class MemInverse : public MemBranchState {
 public:
  // reversal_deadband [m] >= 0: a retreat of y_ref by no more than this from its extremum is
  // answered by holding u (tracking error <= deadband meanwhile) instead of starting a branch.
  // The model driven by u still sees the same branches (a held u is a hold). Default 0: the paper.
  explicit MemInverse(const MemParams& params = {}, double reversal_deadband = 0.0);

  // Virgin state at y0: u0 on the skeleton, the inverse of MemModel::reset(u0).
  void reset(double y0 = 0.0) noexcept;
  // State right after a branching point at (y_origin [m], u_origin [V]) (Theorem 10 starts here).
  void reset_to_branch(double y_origin, double u_origin) noexcept;
  // State on the branch that began at u_origin [V] and passes through (u_now [V], y_now [m]),
  // moving away from u_origin: a stage measured there (e.g. after an identification input whose
  // last reversal was at u_origin) is continued without a branch of its own and without a step
  // in u (the next call starts from u_now exactly). u_now == u_origin is reset_to_branch.
  void continue_branch(double u_origin, double u_now, double y_now) noexcept;

  double inverse(double y_ref) noexcept;

  // Validates, then keeps the branch origin's input and the current u, shifting the origin's
  // output so the new curve passes through the current point, as MemModel::set_params does: a
  // model and its inverse swapped at the same sample stay exact inverses, and u does not jump.
  void set_params(const MemParams& params);

  double reference() const noexcept { return y_ref_; }  // last y_ref [m]
  double output() const noexcept { return u_; }         // last u [V]
  int direction() const noexcept { return direction_; }

 private:
  double curve_inverse(double y) noexcept;  // u on the current branch (or skeleton) at y
  double solve_run(double rise) noexcept;   // F^-1 with a warm start from the previous solve

  double deadband_;
  double u_ = 0.0;
  double y_at_u_ = 0.0;  // the model's output at u_ (the y_ref that produced it): next branching point
  double y_ref_ = 0.0;
  int direction_ = 0;  // of u (= of y along a branch): +1, -1, 0 = not yet known
  // Warm start: the last point where F, M and p^c3 were evaluated (see solve_run).
  bool warm_ = false;
  double warm_p_ = 0.0, warm_f_ = 0.0, warm_m_ = 0.0, warm_pc3_ = 0.0;
};

}  // namespace hystloop
