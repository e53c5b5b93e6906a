#pragma once
// Per-call timing for Google Benchmark: the benchmark's own figure is a mean, but
// a 10 kHz loop cares about the worst case. Wrap each call in SampleTimer::time()
// and report() adds p50/p99/max (ns) as counters next to the mean.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <vector>

namespace hystloop::bench {

class SampleTimer {
 public:
  explicit SampleTimer(std::size_t reserve = 1u << 22) { ns_.reserve(reserve); }

  template <class F>
  void time(F&& f) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    const auto t1 = std::chrono::steady_clock::now();
    if (ns_.size() < ns_.capacity()) {
      ns_.push_back(static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count()));
    }
  }

  // Adds p50_ns, p99_ns, p999_ns and max_ns counters (the clock read itself, ~20 ns, is included).
  void report(benchmark::State& state) {
    if (ns_.empty()) return;
    std::sort(ns_.begin(), ns_.end());
    auto q = [&](double p) { return ns_[static_cast<std::size_t>(p * static_cast<double>(ns_.size() - 1))]; };
    state.counters["p50_ns"] = q(0.50);
    state.counters["p99_ns"] = q(0.99);
    state.counters["p999_ns"] = q(0.999);
    state.counters["max_ns"] = ns_.back();
  }

 private:
  std::vector<double> ns_;
};

// Calls `call(sample)` once per benchmark iteration, cycling through `samples` (prepared
// outside the timed loop), and reports the per-call percentiles.
template <class F>
void time_per_sample(benchmark::State& state, const std::vector<double>& samples, F&& call) {
  SampleTimer timer;
  std::size_t i = 0;
  for (auto _ : state) {
    timer.time([&] { benchmark::DoNotOptimize(call(samples[i])); });
    i = (i + 1 == samples.size()) ? 0 : i + 1;
  }
  timer.report(state);
}

}  // namespace hystloop::bench
