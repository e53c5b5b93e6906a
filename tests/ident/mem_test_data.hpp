#pragma once
// Test data for the identification tests: the paper's identification input and a closed-form
// MEM branch generator written independently of common/models (so a bug shared by model and
// fitter cannot hide), plus seeded sensor noise.

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "models/mem.hpp"

namespace hystloop::testdata {

// u = amplitude sin(2 pi f t), t = k / fs, k = 0 .. duration * fs - 1.
inline std::vector<double> sine_input(double amplitude_V, double frequency_Hz, double sample_rate_Hz, double duration_s,
                                      double offset_V = 0.0) {
  const auto n = static_cast<std::size_t>(std::llround(duration_s * sample_rate_Hz));
  std::vector<double> u(n);
  for (std::size_t k = 0; k < n; ++k) {
    u[k] = offset_V +
           amplitude_V * std::sin(2.0 * std::numbers::pi * frequency_Hz * static_cast<double>(k) / sample_rate_Hz);
  }
  return u;
}

// The paper's identification experiment (Section V-B): 250 sin(20 pi t) V, 10 kHz, 2 s.
inline std::vector<double> paper_identification_input() { return sine_input(250.0, 10.0, 1e4, 2.0); }

// Rate-independent MEM branches: y = y_i + s (c1 p + c2 p^(c3+1)/(c3+1)), p = |u - u_i|, with
// (u_i, y_i) the last extremum (the sample before the direction changed). The virgin part
// starts at (u_0, 0) with the same law.
inline std::vector<double> mem_branches(const std::vector<double>& u, const MemParams& p) {
  std::vector<double> y(u.size(), 0.0);
  if (u.empty()) return y;
  auto inc = [&](double d) { return p.c1 * d + p.c2 * std::pow(d, p.c3 + 1.0) / (p.c3 + 1.0); };
  double u0 = u[0], y0 = 0.0, dir = 0.0;
  for (std::size_t k = 1; k < u.size(); ++k) {
    const double step = u[k] - u[k - 1];
    const double s = step > 0.0 ? 1.0 : (step < 0.0 ? -1.0 : 0.0);
    if (s != 0.0 && dir != 0.0 && s != dir) {
      u0 = u[k - 1];
      y0 = y[k - 1];
    }
    if (s != 0.0) dir = s;
    y[k] = y0 + (dir >= 0.0 ? 1.0 : -1.0) * inc(std::abs(u[k] - u0));
  }
  return y;
}

// The project's forward MEM (common/models/mem.hpp, not the independent generator above) from
// rest at 0 V: y for every u.
inline std::vector<double> model_output(const MemParams& truth, const std::vector<double>& u) {
  MemModel model(truth);
  model.reset(0.0);
  std::vector<double> y(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) y[k] = model.forward(u[k]);
  return y;
}

inline void add_noise(std::vector<double>& y, double rms_m, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, rms_m);
  for (double& v : y) v += n(rng);
}

// A piezo-like MEM: slope 4 nm/V at a reversal, 1.5x that after 500 V.
inline MemParams piezo_truth() {
  MemParams p{};
  p.c1 = 4.0e-9;
  p.c3 = 0.8;
  p.c2 = 0.5 * p.c1 / std::pow(500.0, p.c3);
  return p;
}

inline double rel_err(double est, double truth) { return std::abs(est - truth) / std::abs(truth); }

}  // namespace hystloop::testdata
