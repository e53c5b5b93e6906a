#pragma once
// The exact inverse of any accepted sampled stage (models/linear_stage.hpp), using the reference's
// preview: the compensator plans 50 ms (500 ticks at 10 kHz) ahead, so when w_k is computed the
// reference is known up to tick k + preview_ticks.
//
// WHY EXACT STABLE INVERSION. Write the sampled stage (y_k at the end of tick k, w_k held over
// tick k) as
//   G(z) = z^-d K prod_i (1 - z_i z^-1) / prod_j (1 - p_j z^-1)
// (d whole ticks of delay; the rational part is biproper, K = D != 0). Its inverse has the poles of
// G as zeros (an FIR over the reference, always fine) and the zeros of G as poles. A zero inside
// the unit circle (every sampling zero of a delay-free stage, -0.93 for Banning's) is inverted
// causally: a stable IIR section. A zero OUTSIDE (a continuous right-half-plane zero; the sampling
// zero that a fractional delay pushes beyond -1) is inverted ANTI-causally:
// 1 / (1 - z_o z^-1) = -(z / z_o) sum_j (z / z_o)^j, a series in FUTURE references that converges
// like |1 / z_o|^j, truncated to the preview. The advance z^d of the delay and one tick per outside
// zero also come out of the preview. This bilateral inverse is the only stable one whose response
// is 1 / G at every frequency, hence the only one with which the stage reproduces the reference at
// every tick end; ZPETC (which cancels the phase but not the gain of the outside zeros) and a
// regularised preview inverse both leave an error of the size of the reference's content above
// their bandwidth, where the compensator wants 1e-9.
//
// Its price is the gain 1 / |G| near half the tick rate, large when a sampling zero is near -1
// (so is that of any exact method, causal or not). Measured at 10 kHz (gain() at 5 kHz):
//   stage                                      zeros of the rational part     |1/G| at 5 kHz   taps
//   z0 = -0.99, pole 0.5 (discrete)            -0.99                          597              1
//   Banning 1.72 kHz, zeta 0.094               -0.932, 0                      79               1
//   780 Hz z 0.03 + 2.4 kHz z 0.02, no delay   -0.980, 0.68 +- 0.70i, 0       323              1
//     the same, delay 1.5 ticks                -4.78 (outside), -0.20, ...    7.5              26
//     the same, delay 0.25 / 0.75 tick         -2.08 / -17.5 (outside), ...   10.4 / 9.9       54 / 14
//   RHP zero 3 kHz, mode 1 kHz, pole 2 kHz     8.59 (outside), -0.40, 0       31               19
// (taps: anti-causal taps needed for a bound of 1e-17.) A half-tick delay thus turns the delay-free
// stage's -0.98 into -4.78 and divides the Nyquist gain by 40. Truncation against the preview for a
// zero at z = 1.2: bound 2.6e-2 at N = 20, 1.1e-4 at 50, 1.2e-8 at 100, 1.3e-12 at 150 (refused),
// 1.5e-16 at 200, i.e. (1 / 1.2)^N. Driven by the inverse, the stage reproduces a 1e-6 reference of
// sines below 500 Hz to 1e-21 (1e-15 relative) in tests/models/preview_inverse_test.cpp.
// Exactness is what the caller asked for; a smooth reference (as the planner's is) has nothing at
// 5 kHz to amplify.
//
// Truncation: with L anti-causal taps h_0..h_L of 1 / prod_o (1 - z/z_o), the product of G and
// the inverse is 1 - E(z), E an FIR of m taps (m outside zeros) whose l1 norm bounds the error:
// |y_k - r_k| <= truncation_error_bound() * max |r| over the window. A preview shorter than
// d + m ticks, or one that leaves the bound above kMaxTruncationError, is refused, naming the
// preview needed. A zero ON the unit circle (within kMinZeroDistance) is refused: the stage does not
// pass that frequency and nothing can restore it.
//
// Per tick: one dot product over the anti-causal taps (only as many as reach 1e-17), then second-
// order sections, each pairing an inside zero of the stage (the inverse's pole) with the stage's
// pole nearest to it (the inverse's zero). Sections rather than one FIR over the stage's
// denominator and one IIR over the inside zeros: for the sixteen-state stage of the tests (eight
// modes, |p| ~ 0.99) the worst |y - r| for a 1e-6 reference fell from 4.8e-16 to 3.4e-20.
// Fixed-size, allocation and throw free.
//
// Optional zero-phase low-pass of the reference, reference_bandwidth_hz (DEFAULT 0 = OFF, so that
// the stage reproduces the reference itself): a symmetric Blackman-windowed sinc of half-length
// M = ceil(4 / (bandwidth dt)) ticks (40 at 1 kHz and 10 kHz), unit DC gain; measured: 0.998 up
// to 0.7 times the bandwidth, -6 dB at it, -55 dB at 1.3 times and below -75 dB from 1.5 times on. It is convolved with
// the anti-causal series, so it costs M more ticks of preview and M ticks of past reference; the stage then reproduces
// the FILTERED reference (reference_lowpass() gives the taps). Use it when the reference may carry content near half
// the tick rate that the inverse's gain (table above) would amplify.

#include <array>
#include <cstdint>
#include <span>

#include "models/linear_stage.hpp"

namespace hystloop {

class PreviewStageInverse {
 public:
  static constexpr std::int64_t kMaxPreviewTicks = 2048;
  static constexpr double kMaxTruncationError = 1e-12;  // relative to max |r| over the window
  static constexpr double kMinZeroDistance = 1e-6;      // | |z| - 1 | of a zero ON the unit circle
  static constexpr int kMaxLowPassHalfLength = 1024;    // ticks (the lowest bandwidth: 39 Hz at 10 kHz)

  // Throws ParameterError: "preview_ticks" (outside [0, kMaxPreviewTicks], shorter than the delay
  // plus the outside zeros, or leaving the truncation bound above kMaxTruncationError: the message
  // names the preview needed; the low-pass's M ticks count too), "stage" (a zero on the unit
  // circle), "reference_bandwidth_hz" (not 0 and outside [4 / (kMaxLowPassHalfLength dt), 0.5 / dt)).
  PreviewStageInverse(const DiscreteLinearStage& stage, std::int64_t preview_ticks,
                      double reference_bandwidth_hz = 0.0);

  // At rest at y0: the reference has been y0 for ever, up to tick k + preview_ticks.
  void reset(double y0) noexcept;
  // r_future is the reference at tick k + preview_ticks; returns w_k, the input of tick k, such that
  // the stage's position at the end of tick k is r_k. A non-finite r_future returns the last input
  // and leaves the state untouched. Allocation and throw free.
  double step(double r_future) noexcept;

  std::int64_t preview_ticks() const noexcept { return preview_; }
  // |y_k - r_k| <= bound * max |r_j| over the window (rounding aside; r filtered when the low-pass
  // is on, whose l1 norm the bound includes).
  double truncation_error_bound() const noexcept { return bound_; }
  int anticausal_taps() const noexcept { return taps_; }  // h_0 .. h_{taps-1}
  int outside_zeros() const noexcept { return outside_; }
  double reference_bandwidth_hz() const noexcept { return bandwidth_hz_; }
  // The low-pass's taps g_{-M} .. g_M (applied as sum_j g_j r_{k+j}); one tap of 1 when off.
  std::span<const double> reference_lowpass() const noexcept {
    return {lowpass_.data(), static_cast<std::size_t>(2 * half_ + 1)};
  }
  double last_input() const noexcept { return w_prev_; }
  // |1 / G| at f [Hz]: what the inverse multiplies the reference's content at f by.
  double gain(double f_hz) const noexcept;
  const DiscreteLinearStage& stage() const noexcept { return stage_; }

 private:
  static constexpr int kMaxSections = 2 * DiscreteLinearStage::kMaxStates;
  static constexpr std::size_t kRing = static_cast<std::size_t>(kMaxPreviewTicks + kMaxLowPassHalfLength) + 1;

  struct Section {  // u_k = x_k + b1 x_{k-1} + b2 x_{k-2} - a1 u_{k-1} - a2 u_{k-2}
    double b1 = 0.0, b2 = 0.0, a1 = 0.0, a2 = 0.0;
    double x1 = 0.0, x2 = 0.0, u1 = 0.0, u2 = 0.0;
  };

  DiscreteLinearStage stage_;
  std::int64_t preview_ = 0;
  int lead_ = 0;  // delay + outside zeros: r_{k+lead+j} is multiplied by h_j
  int taps_ = 1;  // of h
  double bandwidth_hz_ = 0.0;
  int half_ = 0;          // M
  std::size_t ring_ = 1;  // N + M + 1
  std::array<double, 2 * kMaxLowPassHalfLength + 1> lowpass_{};
  std::array<double, kRing> c_{};  // h convolved with the low-pass: c_i multiplies r_{k+lead-M+i}
  int c_taps_ = 1;
  int outside_ = 0;
  double bound_ = 0.0;
  double scale_ = 1.0;             // 1 / (K prod_o (-z_o))
  std::array<double, kRing> r_{};  // ring of r_{k-M} .. r_{k+N}
  std::size_t head_ = 0;           // where r_{k+N} is
  int sections_ = 0;
  std::array<Section, kMaxSections> section_{};
  double w_prev_ = 0.0;
};

}  // namespace hystloop
