#pragma once
// A smooth test input with many reversals: offset + amplitude * (a weighted sum of four sines
// with random frequencies and phases) / (sum of the weights), so |s - offset| <= amplitude.
// Frequencies are cycles per record; the random draws come from `rng`, so a seed reproduces it.

#include <cmath>
#include <cstddef>
#include <numbers>
#include <random>
#include <vector>

namespace hystloop::testing {

struct SmoothSignalShape {
  double min_cycles = 5.0;  // per record
  double max_cycles = 40.0;
  double min_weight = 0.2;  // of each sine, relative (max 1)
};

inline std::vector<double> smooth_signal(std::mt19937_64& rng, double amplitude, double offset, std::size_t n,
                                         const SmoothSignalShape& shape = {}) {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  std::uniform_real_distribution<double> freq(shape.min_cycles, shape.max_cycles), phase(0.0, kTwoPi),
      weight(shape.min_weight, 1.0);
  double f[4], p[4], a[4], total = 0.0;
  for (int i = 0; i < 4; ++i) {
    f[i] = freq(rng);
    p[i] = phase(rng);
    a[i] = weight(rng);
    total += a[i];
  }
  std::vector<double> s(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / static_cast<double>(n);
    double v = 0.0;
    for (int i = 0; i < 4; ++i) v += a[i] * std::sin(kTwoPi * f[i] * t + p[i]);
    s[k] = offset + amplitude * v / total;
  }
  return s;
}

inline std::vector<double> smooth_signal(std::uint64_t seed, double amplitude, double offset, std::size_t n,
                                         const SmoothSignalShape& shape = {}) {
  std::mt19937_64 rng(seed);
  return smooth_signal(rng, amplitude, offset, n, shape);
}

}  // namespace hystloop::testing
