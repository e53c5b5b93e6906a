#include "models/mem.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/errors.hpp"

namespace hystloop {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr int kMaxNewtonSteps = 100;  // never reached from a factor-2 bound; a hard stop for rounding

double nan() noexcept { return std::numeric_limits<double>::quiet_NaN(); }

// F(p) = c1 p + c2 p^(c3+1)/(c3+1) given pc3 = p^c3.
double rise_from(const MemParams& c, double p, double pc3) noexcept { return p * (c.c1 + c.c2 * pc3 / (c.c3 + 1.0)); }

// Bounds that need no guess: F(p) >= c1 p and F(p) >= c2 p^k / k, so the root of F(p) = rise
// is below both; the smaller is within a factor 2 of the root (one term is >= rise / 2).
double cold_upper_bound(const MemParams& c, double rise) noexcept {
  double p = rise / c.c1;
  if (c.c2 > 0.0) {
    const double k = c.c3 + 1.0;
    p = std::min(p, std::pow(k * rise / c.c2, 1.0 / k));
  }
  return p;
}

struct NewtonResult {
  double p;       // the root
  double p_eval;  // last point where F and M were evaluated, with their values (a warm start)
  double f_eval;
  double m_eval;
  double pc3_eval;  // p_eval^c3
};

// Newton on the convex, increasing F. From any start p > 0 the first step lands at or above the
// root (the tangent of a convex function lies below it), and from there every iterate stays above
// the root and decreases monotonically (no bracketing needed), quadratically near the root. The
// error left after a step is ~ (F''/2M) step^2 with F'' = c2 c3 p^(c3-1); we stop once that is
// below a sixteenth of an ulp (margin for F'' changing over the step when c3 < 1).
NewtonResult newton(const MemParams& c, double rise, double p) noexcept {
  NewtonResult r{p, p, 0.0, c.c1, 0.0};
  for (int i = 0; i < kMaxNewtonSteps; ++i) {
    const double pc3 = std::pow(p, c.c3);
    const double m = c.c1 + c.c2 * pc3;
    const double f = rise_from(c, p, pc3);
    const double step = (f - rise) / m;
    r.p_eval = p;
    r.f_eval = f;
    r.m_eval = m;
    r.pc3_eval = pc3;
    double next = p - step;
    if (!(next > 0.0)) next = 0.5 * p;  // only rounding can get here: the root is > 0
    // 16 (F''/2M) step^2 <= eps p, multiplied out (no division on the critical path).
    const bool done = std::abs(step) <= kEps * next || 8.0 * c.c2 * c.c3 * pc3 * step * step <= kEps * p * p * m;
    p = next;
    if (done) break;
  }
  r.p = p;
  return r;
}

// sign(q) F(|q|) / scale: the branch (scale 1) or the skeleton (scale 2) relative to its origin.
double odd_rise(const MemParams& c, double q, double scale) noexcept {
  const double p = std::abs(scale * q);
  return std::copysign(rise_from(c, p, std::pow(p, c.c3)), q) / scale;
}

void validate_deadband(double deadband) { require_non_negative("reversal_deadband", deadband); }

}  // namespace

// ---- MemParams ----------------------------------------------------------------------------------

void MemParams::validate() const {
  require_positive("c1", c1);
  require_non_negative("c2", c2);
  require_positive("c3", c3);
}

double MemParams::slope(double p) const noexcept { return c1 + c2 * std::pow(p, c3); }
double MemParams::branch_rise(double p) const noexcept { return rise_from(*this, p, std::pow(p, c3)); }

double MemParams::branch_run(double rise) const noexcept {
  if (!(rise > 0.0)) return rise == 0.0 ? 0.0 : nan();
  return newton(*this, rise, cold_upper_bound(*this, rise)).p;
}

double MemParams::skeleton(double u) const noexcept { return odd_rise(*this, u, 2.0); }

// ---- Ramberg–Osgood ------------------------------------------------------------------------------

void RambergOsgoodParams::validate() const {
  require_positive("y_star", y_star);
  require_positive("u_star", u_star);
  require_non_negative("alpha", alpha);
  require_finite("gamma", gamma);
  if (!(gamma > 1.0)) throw ParameterError("gamma", "must be > 1 (got " + std::to_string(gamma) + ")");
}

MemParams RambergOsgoodParams::to_mem() const {
  validate();
  MemParams m;
  m.c1 = y_star / u_star;
  m.c2 = m.c1 * alpha * gamma / std::pow(2.0 * u_star, gamma - 1.0);
  m.c3 = gamma - 1.0;
  m.validate();
  return m;
}

RambergOsgoodParams RambergOsgoodParams::from_mem(const MemParams& mem, double u_star) {
  mem.validate();
  require_positive("u_star", u_star);
  RambergOsgoodParams ro;
  ro.u_star = u_star;
  ro.y_star = mem.c1 * u_star;
  ro.gamma = mem.c3 + 1.0;
  ro.alpha = mem.c2 * std::pow(2.0 * u_star, mem.c3) / (mem.c1 * ro.gamma);
  ro.validate();
  return ro;
}

double RambergOsgoodParams::skeleton(double u) const noexcept {
  const double x = u / u_star;
  return y_star * x * (1.0 + alpha * std::pow(std::abs(x), gamma - 1.0));
}

double RambergOsgoodParams::branch(double u, double u_i, double y_i) const noexcept {
  const double x = (u - u_i) / (2.0 * u_star);
  return y_i + 2.0 * y_star * x * (1.0 + alpha * std::pow(std::abs(x), gamma - 1.0));
}

// ---- MemBranchState ------------------------------------------------------------------------------

MemBranchState::MemBranchState(const MemParams& params, double reversal_deadband) : params_(params) {
  params_.validate();
  validate_deadband(reversal_deadband);
}

void MemBranchState::restart(double u_origin, double y_origin, double scale) noexcept {
  u_origin_ = u_origin;
  y_origin_ = y_origin;
  scale_ = scale;
  reversals_ = 0;
}

void MemBranchState::reverse_at(double u, double y) noexcept {
  u_origin_ = u;
  y_origin_ = y;
  scale_ = 1.0;
  ++reversals_;
}

// ---- MemModel ------------------------------------------------------------------------------------

MemModel::MemModel(const MemParams& params, double reversal_deadband)
    : MemBranchState(params, reversal_deadband), detector_(reversal_deadband) {
  reset(0.0);
}

void MemModel::reset(double u0) noexcept {
  detector_.reset(u0, u0 > 0.0 ? 1 : (u0 < 0.0 ? -1 : 0));  // virgin loading from 0 went that way
  restart(0.0, 0.0, 2.0);
  u_ = u0;
  y_ = curve(u0);
  y_extremum_ = y_;
}

void MemModel::reset_to_branch(double u_origin, double y_origin) noexcept {
  detector_.reset(u_origin, 0);
  restart(u_origin, y_origin, 1.0);
  u_ = u_origin;
  y_ = y_origin;
  y_extremum_ = y_origin;
}

double MemModel::curve(double u) const noexcept { return y_origin_ + odd_rise(params_, u - u_origin_, scale_); }

double MemModel::forward(double u) noexcept {
  if (!std::isfinite(u)) return nan();
  const ReversalDetector::Event event = detector_.update(u);
  if (event == ReversalDetector::Event::kReversal) reverse_at(detector_.turning_point(), y_extremum_);
  u_ = u;
  y_ = curve(u);
  if (event != ReversalDetector::Event::kNone) y_extremum_ = y_;
  return y_;
}

void MemModel::set_params(const MemParams& params) {
  params.validate();
  params_ = params;
  y_origin_ += y_ - curve(u_);
  y_extremum_ = curve(detector_.extremum());
}

// ---- MemInverse ----------------------------------------------------------------------------------

MemInverse::MemInverse(const MemParams& params, double reversal_deadband)
    : MemBranchState(params, reversal_deadband), deadband_(reversal_deadband) {
  reset(0.0);
}

void MemInverse::reset(double y0) noexcept {
  restart(0.0, 0.0, 2.0);
  warm_ = false;
  u_ = curve_inverse(y0);
  y_at_u_ = y0;
  y_ref_ = y0;
  direction_ = y0 > 0.0 ? 1 : (y0 < 0.0 ? -1 : 0);  // as MemModel::reset(u0): same sign
}

void MemInverse::reset_to_branch(double y_origin, double u_origin) noexcept {
  restart(u_origin, y_origin, 1.0);
  warm_ = false;
  u_ = u_origin;
  y_at_u_ = y_origin;
  y_ref_ = y_origin;
  direction_ = 0;
}

void MemInverse::continue_branch(double u_origin, double u_now, double y_now) noexcept {
  reset_to_branch(y_now, u_now);
  if (u_now == u_origin) return;
  u_origin_ = u_origin;
  y_origin_ = y_now - odd_rise(params_, u_now - u_origin, 1.0);
  direction_ = u_now > u_origin ? 1 : -1;
}

double MemInverse::solve_run(double rise) noexcept {
  if (!(rise > 0.0)) return 0.0;
  double p;
  if (warm_) {
    // Predictor from the last evaluated point w (F, M, p^c3 cached): the root of the quadratic
    // Taylor model F(w) + M d + F''(w) d^2 / 2 = rise, in its cancellation-free form. Consecutive
    // samples are close, so this is usually within ~1e-9 relative and a single Newton step (one
    // pow) finishes. rise / c1 is an upper bound, the better start just after a reversal.
    const double gap = rise - warm_f_;
    const double f2 = params_.c2 * params_.c3 * warm_pc3_ / warm_p_;  // F''(w)
    const double disc = warm_m_ * warm_m_ + 2.0 * f2 * gap;
    double d = disc > 0.0 ? 2.0 * gap / (warm_m_ + std::sqrt(disc)) : gap / warm_m_;
    if (std::abs(d) < 0.25 * warm_p_) {
      // One Newton step on the cubic Taylor model (F''' = F'' (c3 - 1) / w): for the larger steps
      // of a fast reference this keeps the start close enough for a single pow.
      const double f3 = f2 * (params_.c3 - 1.0) / warm_p_;
      const double t = warm_m_ * d + d * d * (0.5 * f2 + d * f3 / 6.0) - gap;
      const double dt = warm_m_ + d * (f2 + 0.5 * d * f3);
      if (dt > 0.0) d -= t / dt;
    }
    p = std::min(warm_p_ + d, rise / params_.c1);
    if (!(p > 0.0)) p = cold_upper_bound(params_, rise);
  } else {
    p = cold_upper_bound(params_, rise);
  }
  const NewtonResult r = newton(params_, rise, p);
  warm_ = r.p_eval > 0.0;
  warm_p_ = r.p_eval;
  warm_f_ = r.f_eval;
  warm_m_ = r.m_eval;
  warm_pc3_ = r.pc3_eval;
  return r.p;
}

double MemInverse::curve_inverse(double y) noexcept {
  const double q = scale_ * (y - y_origin_);
  return u_origin_ + std::copysign(solve_run(std::abs(q)), q) / scale_;
}

double MemInverse::inverse(double y_ref) noexcept {
  if (!std::isfinite(y_ref)) return nan();
  y_ref_ = y_ref;
  const double s = direction_;
  const double ahead = s * (y_ref - y_at_u_);  // > 0: moving on; < 0: turning back
  if (y_ref == y_at_u_) return u_;             // a hold
  if (direction_ == 0 || ahead >= 0.0) {
    if (direction_ == 0 && !(std::abs(y_ref - y_at_u_) > deadband_)) return u_;
    const double u = curve_inverse(y_ref);
    if (direction_ == 0) {
      if (u == u_) return u_;
      direction_ = u > u_ ? 1 : -1;
    } else if (!(s * (u - u_) > 0.0)) {
      return u_;  // u cannot move on (rounding): hold it, as a model would see a hold
    }
    u_ = u;
    y_at_u_ = y_ref;
    return u;
  }
  if (-ahead <= deadband_) return u_;
  // Turning back: a new branch from (u_, y_at_u_), if u does move back.
  const double p = solve_run(-ahead);
  const double u = u_ - s * p;
  if (u == u_) return u_;
  reverse_at(u_, y_at_u_);
  direction_ = -direction_;
  u_ = u;
  y_at_u_ = y_ref;
  return u;
}

void MemInverse::set_params(const MemParams& params) {
  params.validate();
  params_ = params;
  warm_ = false;
  y_origin_ = y_at_u_ - odd_rise(params_, u_ - u_origin_, scale_);
}

}  // namespace hystloop
