#pragma once
// Branches of a sampled input: a reversal is where the direction of u changes. u is taken as
// noise-free but may hold (zero steps keep the current direction); an optional dead band makes a
// reversal count only once u has moved more than dead_band_V back from the extremum, for a
// quantised DAC. The reversal sample is the extremum itself (p = 0 there).
//
// Only branches that start at a reversal are returned: the part before the first reversal
// follows the virgin (skeleton) curve, which obeys a different law.

#include <cstddef>
#include <span>
#include <vector>

namespace hystloop {

struct BranchSegment {
  std::size_t begin = 0;   // index of the reversal sample (p = 0)
  std::size_t end = 0;     // one past the last sample of the branch (= next reversal)
  double origin_u = 0.0;   // u at the reversal [V]
  double direction = 1.0;  // +1 ascending, -1 descending
  std::size_t size() const noexcept { return end - begin; }
};

// Reversal indices (extrema) of u in order, by ReversalDetector's rule (models/reversal_detector.hpp).
std::vector<std::size_t> find_reversals(std::span<const double> u, double dead_band_V = 0.0);

// Branches [reversal_i, reversal_{i+1}) and the last one [reversal_last, n); the skeleton is dropped.
std::vector<BranchSegment> split_branches(std::span<const double> u, double dead_band_V = 0.0);

// White-noise RMS of y from its third difference (var = 20 sigma^2 for white noise; a smooth
// signal sampled densely contributes almost nothing). Robust: median absolute value, so the kinks
// at reversals do not count. Returns 0 for fewer than 8 samples.
double estimate_noise_rms(std::span<const double> y);

}  // namespace hystloop
