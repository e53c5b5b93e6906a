#pragma once
// Characteristic features of a stationary hysteresis loop (Banning et al. 2001, Fig. 1 and
// eqs. (14)-(18)) extracted from sampled data u -> y, simulated or measured.
//
// Method (robust to sensor noise on y; u is taken as the applied voltage):
//  1. Reversals of u are found with a hysteresis threshold (reversal_fraction of the span), so
//     noise cannot fake a reversal; samples are split into the ascending and descending branch.
//  2. Each branch is fitted, over all periods given, with a least-squares Chebyshev polynomial
//     y(u) of degree branch_degree on the normalised input x = (u - u_centre) / (span / 2).
//     Averaging thousands of samples is what removes the noise; branches of a rate-independent
//     loop are smooth between its turning points, so a modest degree fits them to far below 1 nm.
//  3. Features follow from the two polynomials: turning points as the mean of both branches at
//     u_min / u_max, centre (14), slope (15), delta (16) by root finding on each branch at
//     y_centre, eta (17) at u_centre, area (18) by exact integration.
// Give spans of u and y of one period or more (any phase, any number of extra samples).
// Not for the per-sample path: it allocates.

#include <cstddef>
#include <span>
#include <string_view>

namespace hystloop {

struct LoopFeatures {
  double u_min = 0.0;     // [V] left turning point
  double u_max = 0.0;     // [V] right turning point
  double y_left = 0.0;    // [m] y^{down,up}, output at u_min
  double y_right = 0.0;   // [m] y^{up,down}, output at u_max
  double u_centre = 0.0;  // [V] (14)
  double y_centre = 0.0;  // [m] (14)
  double slope = 0.0;     // [m/V] zeta (15): (y_right - y_left) / (u_max - u_min)
  double delta = 0.0;     // [V] (16) horizontal aperture at y_centre, ascending minus descending
  double eta = 0.0;       // [m] (17) vertical aperture at u_centre, descending minus ascending
  double area = 0.0;      // [m V] (18), positive for a counter-clockwise loop
};

struct LoopFeatureOptions {
  int branch_degree = 12;          // polynomial degree of each branch fit, 1..16
  double reversal_fraction = 0.1;  // a reversal must retreat this fraction of the span, (0, 0.5)
  void validate() const;           // throws ParameterError naming the field
};

enum class LoopFeatureStatus {
  kOk,
  kNonFinite,       // a sample is NaN or Inf
  kNoExcursion,     // u does not move
  kIncompleteLoop,  // a branch does not cover the whole span: less than one period
  kTooFewSamples,   // a branch has fewer than 3 (degree + 1) samples
  kNoCrossing,      // a fitted branch does not cross y_centre (no horizontal aperture)
};

std::string_view describe(LoopFeatureStatus status) noexcept;

struct LoopFeatureResult {
  LoopFeatureStatus status = LoopFeatureStatus::kOk;
  LoopFeatures features;
  double residual_rms = 0.0;  // [m] of both branch fits: ~ the sensor noise when the fit is good
  std::size_t samples_ascending = 0;
  std::size_t samples_descending = 0;
  std::size_t reversals = 0;  // confirmed turning points inside the span
  bool ok() const noexcept { return status == LoopFeatureStatus::kOk; }
};

// Throws ParameterError when u and y differ in length or the options are invalid; every problem
// with the data itself is reported through the status.
LoopFeatureResult extract_loop_features(std::span<const double> u, std::span<const double> y,
                                        const LoopFeatureOptions& options = {});

}  // namespace hystloop
