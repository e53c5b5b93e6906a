// Per-call cost of the Prandtl–Ishlinskii operator with the paper's 15 play operators (MEM-matched
// weights) and of its exact inverse, on a 10 kHz sampled 1 Hz and 50 Hz sine (+-250 V in,
// +-1.6 um reference). Signals are precomputed; p50/p99/max per call from SampleTimer.
// Target: <= 300 ns.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstddef>
#include <numbers>
#include <vector>

#include "models/mem.hpp"
#include "models/prandtl_ishlinskii.hpp"
#include "sample_timing.hpp"

namespace {

std::vector<double> cosine(double amplitude, double frequency_hz) {
  const auto n = static_cast<std::size_t>(std::lround(1e4 / frequency_hz));
  std::vector<double> s(n);
  for (std::size_t k = 0; k < n; ++k)
    s[k] = -amplitude * std::cos(2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(n));
  return s;
}

hystloop::PiParams pi15() { return hystloop::pi_params_from_mem(hystloop::MemParams::paper_like(), 15, 250.0); }

void BM_Pi15Forward(benchmark::State& state) {
  hystloop::PiModel model(pi15());
  const auto u = cosine(250.0, static_cast<double>(state.range(0)));
  model.reset(u[0]);
  hystloop::bench::time_per_sample(state, u, [&](double s) { return model.forward(s); });
}
BENCHMARK(BM_Pi15Forward)->Arg(1)->Arg(50);

void BM_Pi15Inverse(benchmark::State& state) {
  hystloop::PiInverse inv(pi15());
  const auto y = cosine(1.6e-6, static_cast<double>(state.range(0)));
  inv.reset(y[0]);
  hystloop::bench::time_per_sample(state, y, [&](double s) { return inv.inverse(s); });
}
BENCHMARK(BM_Pi15Inverse)->Arg(1)->Arg(50);

void BM_Pi32ForwardUntimed(benchmark::State& state) {
  hystloop::PiModel model(
      hystloop::pi_params_from_mem(hystloop::MemParams::paper_like(), hystloop::kPiMaxOperators, 250.0));
  const auto u = cosine(250.0, 1.0);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(model.forward(u[i]));
    i = (i + 1 == u.size()) ? 0 : i + 1;
  }
}
BENCHMARK(BM_Pi32ForwardUntimed);

}  // namespace
