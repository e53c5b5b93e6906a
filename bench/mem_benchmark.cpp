// Per-call cost of the MEM model (closed-form branch, one pow) and its Theorem-10 inverse (Newton
// on the branch equation, warm started), on a 10 kHz sampled 1 Hz sine — the paper's reference
// (24), -1.6 um cos(2 pi t), for the inverse; the +-250 V input that produces it for the model —
// and on a fast 50 Hz sine (a reversal every 100 samples, larger steps per sample: worse for the
// warm start). Signals are precomputed; p50/p99/max per call from SampleTimer. Target: <= 100 ns.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstddef>
#include <numbers>
#include <vector>

#include "models/mem.hpp"
#include "sample_timing.hpp"

namespace {

std::vector<double> cosine(double amplitude, double frequency_hz) {
  const auto n = static_cast<std::size_t>(std::lround(1e4 / frequency_hz));  // one period at 10 kHz
  std::vector<double> s(n);
  for (std::size_t k = 0; k < n; ++k)
    s[k] = -amplitude * std::cos(2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(n));
  return s;
}

void BM_MemForward(benchmark::State& state) {
  hystloop::MemModel model(hystloop::MemParams::paper_like());
  const auto u = cosine(250.0, static_cast<double>(state.range(0)));
  model.reset(u[0]);
  hystloop::bench::time_per_sample(state, u, [&](double s) { return model.forward(s); });
}
BENCHMARK(BM_MemForward)->Arg(1)->Arg(50);

void BM_MemInverse(benchmark::State& state) {
  hystloop::MemInverse inv(hystloop::MemParams::paper_like());
  const auto y = cosine(1.6e-6, static_cast<double>(state.range(0)));
  inv.reset(y[0]);
  hystloop::bench::time_per_sample(state, y, [&](double s) { return inv.inverse(s); });
}
BENCHMARK(BM_MemInverse)->Arg(1)->Arg(50);

// Mean cost without the per-call clock reads (the timer adds ~20-40 ns to every figure above).
void BM_MemInverseUntimed(benchmark::State& state) {
  hystloop::MemInverse inv(hystloop::MemParams::paper_like());
  const auto y = cosine(1.6e-6, static_cast<double>(state.range(0)));
  inv.reset(y[0]);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(inv.inverse(y[i]));
    i = (i + 1 == y.size()) ? 0 : i + 1;
  }
}
BENCHMARK(BM_MemInverseUntimed)->Arg(1)->Arg(50);

void BM_MemForwardUntimed(benchmark::State& state) {
  hystloop::MemModel model(hystloop::MemParams::paper_like());
  const auto u = cosine(250.0, static_cast<double>(state.range(0)));
  model.reset(u[0]);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(model.forward(u[i]));
    i = (i + 1 == u.size()) ? 0 : i + 1;
  }
}
BENCHMARK(BM_MemForwardUntimed)->Arg(1)->Arg(50);

// What SampleTimer itself adds to each timed figure (two steady_clock reads around nothing).
void BM_SampleTimerOverhead(benchmark::State& state) {
  hystloop::bench::SampleTimer timer;
  double x = 0.0;
  for (auto _ : state) {
    timer.time([&] { benchmark::DoNotOptimize(x); });
  }
  timer.report(state);
}
BENCHMARK(BM_SampleTimerOverhead);

}  // namespace
