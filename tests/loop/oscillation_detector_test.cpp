// The servo's oscillation detector: the high-pass's response, a ringing servo found within its hold
// with its frequency, the tracking band and a servo under the bound left alone, once per trip.
#include "loop/oscillation_detector.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

#include "core/errors.hpp"

namespace hystloop {
namespace {

constexpr double kRate = 1e4;

OscillationLimit five_volts() {  // 5 V RMS above 300 Hz for 20 ms
  OscillationLimit l;
  l.rms_V = 5.0;
  return l;
}

double gain_at(const BiquadCoefficients& c, double f_hz) {
  const std::complex<double> z = std::polar(1.0, -2.0 * std::numbers::pi * f_hz / kRate);  // z^-1
  return std::abs((c.b0 + c.b1 * z + c.b2 * z * z) / (1.0 + c.a1 * z + c.a2 * z * z));
}

// Ticks until the detector trips on amplitude * sin(2 pi f t) (-1: not within `ticks`).
std::int64_t ticks_to_trip(OscillationDetector& d, double amplitude_V, double f_hz, std::int64_t ticks = 10000) {
  for (std::int64_t k = 0; k < ticks; ++k) {
    if (d.observe(amplitude_V * std::sin(2.0 * std::numbers::pi * f_hz * static_cast<double>(k) / kRate))) return k;
  }
  return -1;
}

TEST(OscillationDetector, TheHighPassIsButterworthAtItsCorner) {
  const BiquadCoefficients c = design_highpass(300.0, kRate);
  EXPECT_NEAR(gain_at(c, 300.0), 1.0 / std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(gain_at(c, kRate / 2.0), 1.0, 1e-12);
  EXPECT_NEAR(gain_at(c, 1e-9), 0.0, 1e-12);
  EXPECT_NEAR(gain_at(c, 30.0), 0.01, 0.001);  // 40 dB a decade below the corner
}

TEST(OscillationDetector, ARingingServoIsFoundWithinItsHoldAndItsFrequencyNamed) {
  OscillationDetector d(five_volts(), kRate);
  const std::int64_t k = ticks_to_trip(d, 10.0, 1000.0);  // 7.1 V RMS
  // The mean square reaches 5^2 of 7.1^2 after ~0.7 of its 5 ms time constant, then 20 ms beyond.
  EXPECT_GE(k, 200);
  EXPECT_LE(k, 200 + 50);
  EXPECT_NEAR(d.frequency_hz(), 1000.0, 10.0);
  EXPECT_GT(d.tripped_rms_V(), 5.0);
  EXPECT_LT(d.tripped_rms_V(), 7.5);
  EXPECT_FALSE(d.observe(100.0)) << "one trip until reset";
  d.reset();
  EXPECT_GE(ticks_to_trip(d, 10.0, 2200.0), 200);
  EXPECT_NEAR(d.frequency_hz(), 2200.0, 22.0);
}

TEST(OscillationDetector, AGrowingOscillationAtHalfTheTickRateIsFound) {
  // A loop with a closed-loop pole at -1.05: the output alternates and grows 5 % a tick.
  OscillationDetector d(five_volts(), kRate);
  double u = 1e-3;
  std::int64_t k = 0;
  for (; k < 2000 && !d.observe(u); ++k) u *= -1.05;
  EXPECT_LT(k, 2000);
  EXPECT_NEAR(d.frequency_hz(), 5000.0, 50.0);
}

TEST(OscillationDetector, TrackingAndAQuietServoAreLeftAlone) {
  OscillationDetector d(five_volts(), kRate);
  EXPECT_EQ(ticks_to_trip(d, 5.6, 1000.0), -1);  // 4 V RMS: under the bound
  d.reset();
  EXPECT_EQ(ticks_to_trip(d, 100.0, 50.0), -1);  // the tracking band: 2.8 % of it passes
  d.reset();
  // 7.1 V RMS for 15 ms, then quiet: beyond the bound for ~15 ms (the mean square rises and falls
  // within its 5 ms time constant), not the 20 ms of the hold.
  EXPECT_EQ(ticks_to_trip(d, 10.0, 2000.0, 150), -1);
  EXPECT_EQ(ticks_to_trip(d, 0.0, 0.0), -1);
  OscillationLimit off;
  off.rms_V = 0.0;
  OscillationDetector none(off, kRate);
  EXPECT_EQ(ticks_to_trip(none, 200.0, 1000.0), -1);
  EXPECT_FALSE(none.observe(std::nan("")));
}

TEST(OscillationDetector, BadLimitsAreRefusedNamingTheKey) {
  const auto field_of = [](OscillationLimit l) {
    try {
      l.validate(kRate);
    } catch (const ParameterError& e) {
      return e.field();
    }
    return std::string("accepted");
  };
  OscillationLimit l;
  EXPECT_EQ(field_of(l), "accepted");
  l.rms_V = -1.0;
  EXPECT_EQ(field_of(l), "bridge.oscillation_rms_V");
  l = {};
  l.above_hz = 4600.0;
  EXPECT_EQ(field_of(l), "bridge.oscillation_above_hz");
  l = {};
  l.hold_s = 0.001;
  EXPECT_EQ(field_of(l), "bridge.oscillation_hold_s");
  l.rms_V = 0.0;
  EXPECT_EQ(field_of(l), "accepted");  // off: the rest is not used
}

}  // namespace
}  // namespace hystloop
