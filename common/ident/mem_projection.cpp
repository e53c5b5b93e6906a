#include "ident/mem_projection.hpp"

#include <algorithm>

#include <cmath>

namespace hystloop::detail {

LinearPart constrained_pair(double saa, double sab, double sbb, double say, double sby, double syy,
                            double c1_floor) noexcept {
  auto rss = [&](double c1, double c2) {
    return syy - 2.0 * (c1 * say + c2 * sby) + c1 * c1 * saa + 2.0 * c1 * c2 * sab + c2 * c2 * sbb;
  };
  const double det = saa * sbb - sab * sab;
  if (det > 1e-13 * saa * sbb) {
    const double c1 = (sbb * say - sab * sby) / det;
    const double c2 = (saa * sby - sab * say) / det;
    if (c1 >= c1_floor && c2 >= 0.0) return {c1, c2, rss(c1, c2), false};
  }
  // Edge c2 = 0: best c1 >= floor. Edge c1 = floor: best c2 >= 0.
  const double e1_c1 = saa > 0.0 ? std::max(say / saa, c1_floor) : c1_floor;
  const double e2_c2 = sbb > 0.0 ? std::max((sby - c1_floor * sab) / sbb, 0.0) : 0.0;
  const double r1 = rss(e1_c1, 0.0), r2 = rss(c1_floor, e2_c2);
  return r1 <= r2 ? LinearPart{e1_c1, 0.0, r1, true} : LinearPart{c1_floor, e2_c2, r2, true};
}

double pow_from_log(double log_x, double e) noexcept { return log_x == kLogZero ? 0.0 : std::exp(e * log_x); }

void IntegratedData::precompute() {
  const std::size_t nb = groups();
  sum_a.assign(nb, 0.0);
  sum_y.assign(nb, 0.0);
  saa = say = syy = 0.0;
  for (std::size_t b = 0; b < nb; ++b) {
    double sa = 0.0, sy = 0.0;
    for (std::size_t k = group_begin[b]; k < group_begin[b + 1]; ++k) {
      const double a = s[k] * p[k];
      sa += a;
      sy += y[k];
      saa += a * a;
      say += a * y[k];
      syy += y[k] * y[k];
    }
    const double n = static_cast<double>(group_begin[b + 1] - group_begin[b]);
    sum_a[b] = sa;
    sum_y[b] = sy;
    saa -= sa * sa / n;
    say -= sa * sy / n;
    syy -= sy * sy / n;
  }
}

LinearPart IntegratedData::project(double c3) const noexcept {
  const double e = c3 + 1.0;
  const double inv_e = 1.0 / e;
  double sbb = 0.0, sab = 0.0, sby = 0.0;
  const std::size_t nb = groups();
  for (std::size_t b = 0; b < nb; ++b) {
    double sb = 0.0;
    for (std::size_t k = group_begin[b]; k < group_begin[b + 1]; ++k) {
      const double bk = s[k] * pow_from_log(log_p[k], e) * inv_e;
      sb += bk;
      sbb += bk * bk;
      sab += s[k] * p[k] * bk;
      sby += y[k] * bk;
    }
    const double n = static_cast<double>(group_begin[b + 1] - group_begin[b]);
    sbb -= sb * sb / n;
    sab -= sum_a[b] * sb / n;
    sby -= sum_y[b] * sb / n;
  }
  const double floor = saa > 0.0 ? c1_floor_fraction * std::max(say / saa, 0.0) : 0.0;
  LinearPart out = constrained_pair(saa, sab, sbb, say, sby, syy, floor);
  if (out.residual_ss < 0.0) out.residual_ss = 0.0;
  return out;
}

std::vector<double> IntegratedData::offsets(double c1, double c2, double c3) const {
  const double e = c3 + 1.0;
  std::vector<double> o(groups(), 0.0);
  for (std::size_t b = 0; b < groups(); ++b) {
    double sum = 0.0;
    for (std::size_t k = group_begin[b]; k < group_begin[b + 1]; ++k) {
      sum += y[k] - s[k] * (c1 * p[k] + c2 * pow_from_log(log_p[k], e) / e);
    }
    o[b] = sum / static_cast<double>(group_begin[b + 1] - group_begin[b]);
  }
  return o;
}

double derivative_regressor(double log_pa, double log_pb, double inv_dp, double c3) noexcept {
  const double e = c3 + 1.0;
  return (pow_from_log(log_pb, e) - pow_from_log(log_pa, e)) * inv_dp / e;
}

double derivative_regressor_dc3(double log_pa, double log_pb, double inv_dp, double c3) noexcept {
  const double e = c3 + 1.0;
  const double fb = pow_from_log(log_pb, e), fa = pow_from_log(log_pa, e);
  const double lb = log_pb == kLogZero ? 0.0 : fb * log_pb;  // x^e ln x -> 0 as x -> 0
  const double la = log_pa == kLogZero ? 0.0 : fa * log_pa;
  return ((lb - la) / e - (fb - fa) / (e * e)) * inv_dp;
}

void DerivativeData::precompute() {
  sum_z = sum_zz = 0.0;
  for (double v : z) {
    sum_z += v;
    sum_zz += v * v;
  }
}

LinearPart DerivativeData::project(double c3) const noexcept {
  double sg = 0.0, sgg = 0.0, sgz = 0.0;
  for (std::size_t k = 0; k < z.size(); ++k) {
    const double g = derivative_regressor(log_pa[k], log_pb[k], inv_dp[k], c3);
    sg += g;
    sgg += g * g;
    sgz += g * z[k];
  }
  const double n = static_cast<double>(z.size());
  // z = c1 + c2 g in the uncentred sums (the constant regressor is the first one).
  const double floor = c1_floor_fraction * std::max(sum_z / n, 0.0);
  LinearPart out = constrained_pair(n, sg, sgg, sum_z, sgz, sum_zz, floor);
  if (out.residual_ss < 0.0) out.residual_ss = 0.0;
  return out;
}

}  // namespace hystloop::detail
