#pragma once
// A second-order notch (biquad), designed by the bilinear transform of
//   H(s) = (s^2 + W^2) / (s^2 + (W / q) s + W^2),   W = (2 / T) tan(pi f0 T)
// with the centre prewarped, so that the digital filter's zero sits exactly at f0 whatever f0 T:
// |H| = 0 at f0, 1 at DC and at Nyquist, 1/sqrt(2) at the two frequencies the transform maps the
// analogue band edges to (W1 W2 = W^2, W2 - W1 = W / q). The servo uses it to take the gain out
// of the stage's undamped resonance. step() is allocation- and throw-free.

namespace hystloop {

struct BiquadCoefficients {
  double b0 = 1.0, b1 = 0.0, b2 = 0.0;  // numerator
  double a1 = 0.0, a2 = 0.0;            // denominator, a0 = 1
};

// The notch at centre_hz with quality factor q (centre / width) for sample rate rate_hz.
// Requires 0 < centre_hz < rate_hz / 2 and q > 0 (the caller validates; FeedbackGains does).
BiquadCoefficients design_notch(double centre_hz, double q, double rate_hz) noexcept;

// A second-order Butterworth high-pass at corner_hz (-3 dB, prewarped) by the same transform;
// NotchFilter runs any such biquad. Requires 0 < corner_hz < rate_hz / 2 (the caller validates).
BiquadCoefficients design_highpass(double corner_hz, double rate_hz) noexcept;

class NotchFilter {
 public:
  NotchFilter() = default;
  explicit NotchFilter(const BiquadCoefficients& c) noexcept : c_(c) {}

  // The output for input x if it were the next sample, without stepping.
  double peek(double x) const noexcept { return c_.b0 * x + s1_; }
  double step(double x) noexcept {
    // Transposed direct form II: two states, no cancellation between large terms.
    const double y = c_.b0 * x + s1_;
    s1_ = c_.b1 * x - c_.a1 * y + s2_;
    s2_ = c_.b2 * x - c_.a2 * y;
    return y;
  }
  // The state of a filter that has seen the constant input `value` for ever (its output is
  // `value` too: the gain at DC is 1). What a filter switched in on a running signal starts from.
  void settle_at(double value) noexcept {
    s2_ = (c_.b2 - c_.a2) * value;
    s1_ = (c_.b1 - c_.a1) * value + s2_;
  }
  void reset() noexcept { s1_ = s2_ = 0.0; }
  const BiquadCoefficients& coefficients() const noexcept { return c_; }

 private:
  BiquadCoefficients c_{};
  double s1_ = 0.0, s2_ = 0.0;
};

}  // namespace hystloop
