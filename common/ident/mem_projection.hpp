#pragma once
// Internals of fit_mem(): the scaled data of each form and its variable-projection residual.
// Scaling (p~ = p / U, y~ = y / Y) keeps every regressor in [0, 1] so the 2x2 normal equations
// and Ceres' tolerances are well conditioned; c1 = c1~ Y / U, c2 = c2~ Y / U^(c3+1).

#include <cstddef>
#include <limits>
#include <vector>

namespace hystloop::detail {

inline constexpr double kLogZero = -std::numeric_limits<double>::infinity();

// x^e from ln x, with x = 0 -> 0 (e > 0 here).
double pow_from_log(double log_x, double e) noexcept;

struct LinearPart {
  double c1 = 0.0;  // scaled
  double c2 = 0.0;
  double residual_ss = 0.0;  // sum of squared projected residuals (scaled units)
  bool constrained = false;  // the optimum sits on c1 = floor or c2 = 0
};

// The least-squares (c1, c2) of a two-regressor problem with centred sums, kept in the MEM
// domain c1 >= c1_floor, c2 >= 0: on data that is not exactly MEM-shaped (a Coleman-Hodgdon
// stage, whose slope saturates) the unconstrained optimum can leave it (c1 < 0 with c3 -> 0),
// and a slope near zero after a reversal makes the feedforward's voltage jump at every reversal.
// The constrained optimum of this convex quadratic lies inside or on one of the two edges.
LinearPart constrained_pair(double saa, double sab, double sbb, double say, double sby, double syy,
                            double c1_floor) noexcept;

// Integrated branch form: y~_k = o_b + s_k (c1~ p~_k + c2~ p~_k^(c3+1)/(c3+1)).
struct IntegratedData {
  std::vector<double> p, log_p, s, y;    // scaled, branch after branch
  std::vector<std::size_t> group_begin;  // branch b is [group_begin[b], group_begin[b+1])
  // Sums that do not depend on c3 (per branch and centred).
  std::vector<double> sum_a, sum_y;
  double saa = 0.0, say = 0.0, syy = 0.0;
  double c1_floor_fraction = 0.0;  // c1 >= this x the data's mean slope (say / saa)

  std::size_t groups() const noexcept { return group_begin.empty() ? 0 : group_begin.size() - 1; }
  void precompute();
  LinearPart project(double c3) const noexcept;
  // Least-squares branch offsets for given scaled parameters.
  std::vector<double> offsets(double c1, double c2, double c3) const;
};

// Derivative form: z~_k = c1~ + c2~ g_k(c3), g_k = mean of p~^c3 over [p~a_k, p~b_k].
struct DerivativeData {
  std::vector<double> log_pa, log_pb, inv_dp, z;  // scaled
  double sum_z = 0.0, sum_zz = 0.0;
  double c1_floor_fraction = 0.0;  // c1 >= this x the mean slope (mean z)

  void precompute();
  LinearPart project(double c3) const noexcept;
};

double derivative_regressor(double log_pa, double log_pb, double inv_dp, double c3) noexcept;
// d g / d c3
double derivative_regressor_dc3(double log_pa, double log_pb, double inv_dp, double c3) noexcept;

}  // namespace hystloop::detail
