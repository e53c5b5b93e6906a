#include "loop/oscillation_detector.hpp"

#include <cmath>

#include "core/errors.hpp"

namespace hystloop {

void OscillationLimit::validate(double rate_hz) const {
  require_non_negative("bridge.oscillation_rms_V", rms_V);
  if (!enabled()) return;
  require_in_range("bridge.oscillation_above_hz", above_hz, 10.0, 0.45 * rate_hz);
  require_in_range("bridge.oscillation_hold_s", hold_s, 2.0 * kWindow_s, 1.0);
}

OscillationDetector::OscillationDetector(const OscillationLimit& limit, double rate_hz) noexcept
    : highpass_(design_highpass(limit.above_hz, rate_hz)),
      alpha_(1.0 / (OscillationLimit::kWindow_s * rate_hz)),
      threshold2_(limit.rms_V * limit.rms_V),
      dt_s_(1.0 / rate_hz),
      hold_ticks_(std::llround(limit.hold_s * rate_hz)) {}

bool OscillationDetector::observe(double u_V) noexcept {
  if (threshold2_ == 0.0 || tripped_) return false;
  const double x = highpass_.step(std::isfinite(u_V) ? u_V : 0.0);
  mean_square_ += alpha_ * (x * x - mean_square_);
  if (!(mean_square_ > threshold2_)) {
    beyond_ = crossings_ = 0;
    return false;
  }
  const bool positive = x > 0.0;
  if (beyond_ > 0 && positive != last_positive_) ++crossings_;
  last_positive_ = positive;
  if (++beyond_ < hold_ticks_) return false;
  tripped_ = true;
  frequency_hz_ = static_cast<double>(crossings_) / (2.0 * static_cast<double>(beyond_ - 1) * dt_s_);
  tripped_rms_V_ = std::sqrt(mean_square_);
  return true;
}

void OscillationDetector::reset() noexcept {
  highpass_.reset();
  mean_square_ = 0.0;
  beyond_ = crossings_ = 0;
  tripped_ = false;
}

}  // namespace hystloop
