#include "models/stage_inverse.hpp"

#include "models/preview_inverse.hpp"

#include <cmath>
#include <complex>
#include <numbers>
#include <string>

#include <Eigen/LU>  // determinant

#include "core/errors.hpp"

namespace hystloop {

double DiscreteStage::magnitude(double f_hz, double dt_s) const noexcept {
  const std::complex<double> z = std::polar(1.0, 2.0 * std::numbers::pi * f_hz * dt_s);
  return std::abs((b1 * z + b2) / (z * z + a1 * z + a2));
}

DiscreteStage discretise_zoh(const SecondOrderStageParams& stage, double dt_s) {
  stage.validate();
  require_in_range("dt_s", dt_s, 1e-7, 1.0);
  const ZohMatrices z = zoh_matrices(stage, dt_s);  // the matrices SecondOrderStage steps with
  const Eigen::Matrix2d& phi = z.phi;
  const Eigen::Vector2d& gamma = z.gamma;
  // G(z) = C (zI - Phi)^-1 Gamma with C = [1 0]: C adj(zI - Phi) = [z - Phi22, Phi12].
  DiscreteStage d;
  d.a1 = -phi.trace();
  d.a2 = phi.determinant();
  d.b1 = gamma(0);
  d.b2 = -phi(1, 1) * gamma(0) + phi(0, 1) * gamma(1);
  return d;
}

void StageModel::validate(double dt_s) const {
  if (kind == Kind::kNone) return;
  if (kind == Kind::kLinear) {
    linear.validate(dt_s);
    if (order != BanningOrder::kHysteresisThenStage) {
      throw ParameterError("stage.order",
                           "a linear stage is inverted with the reference's preview, ahead of the "
                           "hysteresis inverse: only hysteresis_then_stage");
    }
    require_in_range("stage.preview_ticks", static_cast<double>(preview_ticks), 0.0,
                     static_cast<double>(PreviewStageInverse::kMaxPreviewTicks));
    if (reference_bandwidth_hz != 0.0) require_positive("stage.reference_bandwidth_hz", reference_bandwidth_hz);
    validate_within("stage.",
                    [&] { stage_preview_ticks(discretise(linear, dt_s), preview_ticks, reference_bandwidth_hz); });
    return;
  }
  if (kind != Kind::kSecondOrder) throw ParameterError("stage.kind", "must be none, second_order or linear");
  validate_within("stage.", [&] { second_order.validate(); });
  const StageInverse check(second_order, dt_s);
}

double StageModel::lowest_resonance_rad_s(double dt_s, bool with_zeros, double max_damping) const {
  if (kind == Kind::kSecondOrder) {
    return second_order.damping_ratio() < max_damping ? second_order.natural_frequency() : 0.0;
  }
  if (kind != Kind::kLinear) return 0.0;
  // From the sampled stage: s = ln(z) / dt, omega_n = |s|, zeta = -Re(s) / |s| (the delay moves no
  // pole or zero, and is left out so that a fine dt_s is never refused for it). The sampling zeros
  // sit near z = -1, at half the tick rate, and never set the minimum.
  LinearStageSpec no_delay = linear;
  no_delay.delay_s = 0.0;
  const DiscreteLinearStage d = discretise(no_delay, dt_s);
  double lowest = 0.0;
  const auto consider = [&](const std::complex<double>& z) {
    if (std::abs(z.imag()) < 1e-12 || std::abs(z) == 0.0) return;
    const std::complex<double> s = std::log(z) / dt_s;
    if (-s.real() / std::abs(s) >= max_damping) return;
    if (lowest == 0.0 || std::abs(s) < lowest) lowest = std::abs(s);
  };
  for (const auto& p : d.poles) consider(p);
  if (with_zeros) {
    for (const auto& z : d.zeros) consider(z);
  }
  return lowest;
}

std::int64_t stage_preview_ticks(const DiscreteLinearStage& stage, std::int64_t wanted, double reference_bandwidth_hz) {
  if (wanted > 0) {
    const PreviewStageInverse check(stage, wanted, reference_bandwidth_hz);  // throws naming the preview needed
    return wanted;
  }
  // The shortest preview that is accepted: acceptance grows with the preview, so bisect.
  const auto accepted = [&](std::int64_t n) {
    try {
      const PreviewStageInverse check(stage, n, reference_bandwidth_hz);
      return true;
    } catch (const ParameterError&) {
      return false;
    }
  };
  std::int64_t hi = PreviewStageInverse::kMaxPreviewTicks;
  if (!accepted(hi)) {
    const PreviewStageInverse check(stage, hi, reference_bandwidth_hz);  // throws the reason
  }
  std::int64_t lo = -1;  // refused (or below the range)
  while (hi - lo > 1) {
    const std::int64_t mid = lo + (hi - lo) / 2;
    (mid >= 0 && accepted(mid) ? hi : lo) = mid;
  }
  return hi;
}

StageInverse::StageInverse(const SecondOrderStageParams& stage, double dt_s)
    : params_(stage), model_(discretise_zoh(stage, dt_s)) {
  const double z0 = model_.sampling_zero();
  if (!(model_.b1 > 0.0) || !std::isfinite(z0) || std::abs(z0) > kMaxSamplingZero) {
    throw ParameterError("stage.c", "the stage (k " + std::to_string(stage.k) + " 1/s^2, c " + std::to_string(stage.c) +
                                        " 1/s) sampled at " + std::to_string(dt_s) +
                                        " s has its sampling zero at z = " + std::to_string(z0) +
                                        "; its inverse would ring at half the tick rate (|z| > " +
                                        std::to_string(kMaxSamplingZero) +
                                        "): check the damping c, or run the feedforward without the stage");
  }
  reset(0.0);
}

void StageInverse::reset(double y0) noexcept {
  r1_ = y0;
  r2_ = y0;
  w_prev_ = y0;
}

double StageInverse::step(double r_k) noexcept {
  if (!std::isfinite(r_k)) return w_prev_;
  const double w = (r_k + model_.a1 * r1_ + model_.a2 * r2_ - model_.b2 * w_prev_) / model_.b1;
  r2_ = r1_;
  r1_ = r_k;
  w_prev_ = w;
  return w;
}

}  // namespace hystloop
