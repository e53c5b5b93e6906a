#include "loop/notch_filter.hpp"

#include <cmath>
#include <numbers>

namespace hystloop {

BiquadCoefficients design_notch(double centre_hz, double q, double rate_hz) noexcept {
  // s = (2 / T) (z - 1) / (z + 1) with K = W T / 2 = tan(pi f0 T), multiplied through by (z + 1)^2.
  const double K = std::tan(std::numbers::pi * centre_hz / rate_hz);
  const double K2 = K * K;
  const double norm = 1.0 + K / q + K2;
  BiquadCoefficients c;
  c.b0 = (1.0 + K2) / norm;
  c.b1 = 2.0 * (K2 - 1.0) / norm;
  c.b2 = c.b0;
  c.a1 = c.b1;
  c.a2 = (1.0 - K / q + K2) / norm;
  return c;
}

BiquadCoefficients design_highpass(double corner_hz, double rate_hz) noexcept {
  // H(s) = s^2 / (s^2 + sqrt(2) W s + W^2), W prewarped: K = tan(pi fc T).
  const double K = std::tan(std::numbers::pi * corner_hz / rate_hz);
  const double K2 = K * K;
  const double norm = 1.0 + std::numbers::sqrt2 * K + K2;
  BiquadCoefficients c;
  c.b0 = 1.0 / norm;
  c.b1 = -2.0 / norm;
  c.b2 = 1.0 / norm;
  c.a1 = 2.0 * (K2 - 1.0) / norm;
  c.a2 = (1.0 - std::numbers::sqrt2 * K + K2) / norm;
  return c;
}

}  // namespace hystloop
