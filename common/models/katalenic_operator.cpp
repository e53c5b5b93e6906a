#include "models/katalenic_operator.hpp"

#include <algorithm>
#include <boost/math/policies/policy.hpp>
#include <boost/math/special_functions/lambert_w.hpp>
#include <cmath>

namespace hystloop {
namespace {

namespace bmp = boost::math::policies;
using NoThrowPolicy = bmp::policy<bmp::domain_error<bmp::ignore_error>, bmp::overflow_error<bmp::ignore_error>,
                                  bmp::evaluation_error<bmp::ignore_error>, bmp::pole_error<bmp::ignore_error>>;

// Below this product k2 M* the direct form k2 M* e^{k2(M* - v~)} with exponent < kLogDomainThreshold
// stays below DBL_MAX (1e8 * e^690 ~ 1e307).
constexpr double kDirectProductLimit = 1e8;

}  // namespace

double lambert_w0_nothrow(double z) noexcept { return boost::math::lambert_w0(z, NoThrowPolicy()); }

double lambert_w0_of_exp(double s) noexcept {
  if (s < kLogDomainThreshold) return lambert_w0_nothrow(std::exp(s));
  // f(w) = w + ln w - s is increasing and concave; Newton from w = s - ln s converges
  // quadratically (relative error ~ (ln s / s)^2 at the start), three steps reach rounding.
  double w = s - std::log(s);
  for (int i = 0; i < 6; ++i) {
    const double step = (w + std::log(w) - s) * w / (w + 1.0);
    w -= step;
    if (std::abs(step) <= 1e-16 * w) break;
  }
  return w;
}

double katalenic_direct_branch(double k2, double m_star, double v_tilde) noexcept {
  if (!(m_star > 0.0)) return v_tilde;  // on the asymptote: W(0) = 0
  const double km = k2 * m_star;
  const double exponent = k2 * (m_star - v_tilde);
  const double w = (exponent < kLogDomainThreshold && km < kDirectProductLimit)
                       ? lambert_w0_nothrow(km * std::exp(exponent))
                       : lambert_w0_of_exp(std::log(km) + exponent);
  return v_tilde - m_star + w / k2;
}

double katalenic_inverse_branch(double k2, double m_star, double ud_tilde) noexcept {
  return ud_tilde - m_star * std::expm1(-k2 * ud_tilde);
}

double KatalenicDirectOperator::apply(double v, double k1, double k2) noexcept {
  memory_.advance(v);
  // M* lies in [0, 2 k1] while the state is inside the loop; the clamp keeps rounding from
  // pushing W's argument below zero.
  const double m_star = std::clamp(memory_.m() + k1, 0.0, 2.0 * k1);
  const double u = memory_.beta_from_tilde(katalenic_direct_branch(k2, m_star, memory_.alpha_tilde(v)));
  memory_.commit(v, u);
  return u;
}

double KatalenicInverseOperator::apply(double ud, double k1, double k2) noexcept {
  memory_.advance(ud);
  const double m_star = std::clamp(k1 - memory_.m(), 0.0, 2.0 * k1);
  const double v = memory_.beta_from_tilde(katalenic_inverse_branch(k2, m_star, memory_.alpha_tilde(ud)));
  memory_.commit(ud, v);
  return v;
}

OperatorRates KatalenicInverseOperator::apply_with_rates(double ud, double ud_dot, double ud_ddot, double k1,
                                                         double k2) noexcept {
  OperatorRates r;
  r.value = apply(ud, k1, k2);
  const double heading = ud_dot > 0.0 ? 1.0 : (ud_dot < 0.0 ? -1.0 : memory_.direction());
  // m = M* e^{-k2 u_d~}: on the current branch from (4); when the rate points the other way the
  // input is at a reversal, where the new branch starts with u_d~ = 0 at the current point.
  double m = 0.0;
  if (heading == memory_.direction()) {
    const double m_star = std::clamp(k1 - memory_.m(), 0.0, 2.0 * k1);
    m = m_star * std::exp(-k2 * memory_.alpha_tilde(ud));
  } else {
    m = std::clamp(k1 + heading * (ud - r.value), 0.0, 2.0 * k1);
  }
  const double slope = 1.0 + k2 * m;
  r.rate = slope * ud_dot;
  r.acceleration = slope * ud_ddot - k2 * k2 * m * ud_dot * std::abs(ud_dot);
  return r;
}

}  // namespace hystloop
