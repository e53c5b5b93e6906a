#pragma once
// Cross-coupling between the axes of an XY(Z) stage, and the decoupling put in front of the
// per-axis inverses. On flexure and tube stages moving one axis moves the others by a few per
// cent. Each axis i has its own (hysteretic, dynamic) displacement s_i [m]; the sensors read
//
//   y = C s,   C(j, i) = C_ji = axis j's output per metre of axis i's own displacement [m/m].
//
// C's diagonal is exactly 1: each axis's own gain belongs to its own per-axis model, so C holds
// only what one axis does to the others. The compensator asks the axes for w = C^{-1} r, so that
// y = C w = r. Identification: ident/coupling_fit.hpp.
//
// Axes are numbered 0, 1, 2 and named x, y, z. Storage is fixed at kMaxAxes x kMaxAxes; only the
// top-left n x n block is the model, the rest is kept at the identity so that couple() and
// decouple() pass the unused entries through unchanged. An AxisCoupling is always valid: its
// constructor validates and computes the inverse once, so the per-sample calls are matrix-vector
// products with no check, no allocation and no throw.

#include <array>
#include <string>
#include <string_view>

#include <Eigen/Core>

namespace hystloop {

inline constexpr int kMaxAxes = 3;  // XY(Z): up to three axes on one tick clock

// |C_ji| above this is not the "few per cent" of a flexure or tube stage but a mislabelled axis or
// a sensor wired to the wrong channel; with it the diagonal still dominates each row of a 2x2.
inline constexpr double kMaxCoupling = 0.5;

// The largest condition number of C accepted. Decoupling multiplies a reference error, and each
// axis's model error, by up to cond(C): a stage coupled by a few per cent has ~1.1, while |C_ji| <=
// 0.5 alone still admits a singular 3x3 (e.g. every off-diagonal -0.5), whose w = C^{-1} r would be
// a small difference of huge commands that saturates the amplifiers.
inline constexpr double kMaxCouplingCondition = 100.0;

using AxisVector = Eigen::Vector3d;  // one value per axis [m]; entries >= n pass through
using AxisMatrix = Eigen::Matrix3d;

// "x", "y", "z" ("?" outside 0..kMaxAxes-1).
std::string_view axis_name(int axis) noexcept;
// A per-axis key or field: axis x's is `field` itself, the others' carry the axis after the
// section ("actuator.u_max_V", 1 -> "actuator.y.u_max_V"; a field without a section gets it in front).
std::string axis_field(std::string_view field, int axis);

// The off-diagonal entries of C by name, as configuration keys spell them: "<from>_to_<to>" is
// C(to, from), the fraction of axis <from>'s own displacement that axis <to>'s sensor reads.
struct CouplingEntry {
  std::string_view name;
  int to;
  int from;
};
inline constexpr std::array<CouplingEntry, 6> kCouplingEntries{
    {{"x_to_y", 1, 0}, {"x_to_z", 2, 0}, {"y_to_x", 0, 1}, {"y_to_z", 2, 1}, {"z_to_x", 0, 2}, {"z_to_y", 1, 2}}};

// ", x -> y +0.03, ..." for the non-zero off-diagonal entries among the first n axes; " none" when
// there are none (for start-up lines: "coupling" + describe_coupling(C, n)).
std::string describe_coupling(const AxisMatrix& c, int n);

// C and its inverse, both fixed-size: copying allocates nothing, so a refitted coupling can be
// assigned between ticks.
class AxisCoupling {
 public:
  // One uncoupled axis.
  AxisCoupling() noexcept = default;
  // n axes (1..kMaxAxes) coupled by the top-left n x n block of c (the rest is ignored). Runs
  // validate() (throws ParameterError naming the field) and computes the inverse.
  AxisCoupling(int n, const AxisMatrix& c);

  // n uncoupled axes: decouple(r) == r exactly.
  static AxisCoupling identity(int n);

  // n in 1..kMaxAxes ("n"); every entry finite, the diagonal exactly 1, |C_ji| <= kMaxCoupling
  // (named "coupling[j][i]"); cond(C) <= kMaxCouplingCondition ("coupling"). The constructor runs
  // it, so it holds for every AxisCoupling; public for code that checks every part of a set.
  void validate() const;

  int n() const noexcept { return n_; }
  const AxisMatrix& matrix() const noexcept { return c_; }            // C
  const AxisMatrix& inverse_matrix() const noexcept { return inv_; }  // C^{-1}
  double condition_number() const;                                    // of the n x n block (2-norm)

  // y = C s: the sensors' reading for the axes' own displacements s [m] (simulation, tests).
  AxisVector couple(const AxisVector& s) const noexcept;
  // w = C^{-1} r: what to ask of each axis's inverse so that the stage reaches r [m]. Called once
  // per tick for all axes; the per-axis loop then runs axis i's inverse on w[i]. A non-finite r[j]
  // gives a non-finite w[i] on every axis i that axis j is coupled to (the loop's safe state takes
  // it from there), and on no other: an exactly zero entry of C^{-1} is skipped.
  AxisVector decouple(const AxisVector& r) const noexcept;

  // One line: "x->y 3.0 %, x->z 0.5 %, y->x -1.0 %, ..." (C_ji as "i->j", every off-diagonal entry
  // of the n x n block, by the moving axis); "x: single axis, no coupling" for n = 1.
  std::string describe() const;

 private:
  int n_ = 1;
  AxisMatrix c_ = AxisMatrix::Identity();
  AxisMatrix inv_ = AxisMatrix::Identity();
};

}  // namespace hystloop
