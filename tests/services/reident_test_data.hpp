#pragma once
// Shared by the re-identifier's unit tests: a small, fast configuration (10 Hz sine, 0.5 s
// window at 10 kHz: ten branches per window) and MEM data from the test generator of
// tests/ident (independent of common/models).

#include <vector>

#include "ident/mem_test_data.hpp"
#include "reidentifier/reident_options.hpp"

namespace hystloop::testdata {

inline MemParams gain_scaled(MemParams p, double gain) {
  p.c1 *= gain;
  p.c2 *= gain;
  return p;
}

inline ReidentOptions small_reident_options(const MemParams& initial) {
  ReidentOptions o;
  o.initial = initial;
  o.rate_hz = 1e4;
  o.window_s = 0.5;
  o.capacity_s = 1.0;
  o.refit_period_s = 1.0;
  o.estimator.window_samples = 5000;
  o.estimator.capacity_samples = 10000;
  return o;
}

// 1 s of u = 250 sin(2 pi 10 t) and the MEM response of `truth` with 1 nm noise.
struct SineRecord {
  std::vector<double> u, y;
};
inline SineRecord sine_record(const MemParams& truth, std::uint64_t seed, double duration_s = 1.0) {
  SineRecord r;
  r.u = sine_input(250.0, 10.0, 1e4, duration_s);
  r.y = mem_branches(r.u, truth);
  add_noise(r.y, 1e-9, seed);
  return r;
}

}  // namespace hystloop::testdata
