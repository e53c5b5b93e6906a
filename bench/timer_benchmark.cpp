// Cost of the timing bookkeeping a 10 kHz loop does every tick: recording one
// latency, the deadline arithmetic, and (once a second) reading percentiles.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "core/latency_stats.hpp"
#include "core/periodic_timer.hpp"

namespace {

std::vector<std::int64_t> latencies() {
  std::mt19937_64 rng(1);
  std::lognormal_distribution<double> d(9.0, 1.0);  // ~8 us median, long tail
  std::vector<std::int64_t> v(4096);
  for (auto& x : v) x = static_cast<std::int64_t>(d(rng));
  return v;
}

void BM_LatencyStatsAdd(benchmark::State& state) {
  const auto v = latencies();
  hystloop::LatencyStats s;
  std::size_t i = 0;
  for (auto _ : state) {
    s.add(v[i++ & 4095]);
  }
  benchmark::DoNotOptimize(s.count());
}
BENCHMARK(BM_LatencyStatsAdd);

// add() as the bridge's clock thread makes it: the ticks of a wake-up back to back, each recording
// its work (~0.6 us, perf on the live loop), after the core ran other processes for milliseconds.
// Arg 0: kB of other memory touched between wake-ups (64: L1 evicted, 4096: L2 too); arg 1: adds
// per wake-up (rt.ticks_per_wake). Only the adds are timed: the time is per wake-up, divide by
// arg 1 for one add.
void BM_LatencyStatsAddAfterOtherWork(benchmark::State& state) {
  const auto touch_bytes = static_cast<std::size_t>(state.range(0)) * 1024;
  const auto adds = static_cast<std::size_t>(state.range(1));
  std::mt19937_64 rng(3);
  std::lognormal_distribution<double> d(std::log(600.0), 0.3);
  std::vector<std::int64_t> v(4096);
  for (auto& x : v) x = static_cast<std::int64_t>(d(rng));
  std::vector<std::uint64_t> other(touch_bytes / sizeof(std::uint64_t) + 1);
  hystloop::LatencyStats s;
  std::size_t i = 0;
  std::uint64_t sink = 0;
  for (auto _ : state) {
    for (std::size_t j = 0; j < other.size(); j += 8) sink += ++other[j];  // a line each
    benchmark::ClobberMemory();
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t a = 0; a < adds; ++a) s.add(v[i++ & 4095]);
    benchmark::ClobberMemory();
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  benchmark::DoNotOptimize(sink);
  benchmark::DoNotOptimize(s.count());
}
// A fixed count: the untimed touch is most of the wall time.
BENCHMARK(BM_LatencyStatsAddAfterOtherWork)
    ->UseManualTime()
    ->Iterations(20'000)
    ->Args({64, 20})
    ->Args({64, 50})
    ->Args({4096, 50});

void BM_LatencyStatsSummary(benchmark::State& state) {
  hystloop::LatencyStats s;
  for (const auto x : latencies()) s.add(x);
  for (auto _ : state) {
    benchmark::DoNotOptimize(s.summary());
  }
}
BENCHMARK(BM_LatencyStatsSummary);

void BM_DeadlineScheduleOnWake(benchmark::State& state) {
  hystloop::DeadlineSchedule schedule(0, 100'000);
  for (auto _ : state) {
    benchmark::DoNotOptimize(schedule.on_wake(schedule.next_deadline_ns() + 3'000));
  }
}
BENCHMARK(BM_DeadlineScheduleOnWake);

void BM_MonotonicNow(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(hystloop::monotonic_ns());
}
BENCHMARK(BM_MonotonicNow);

}  // namespace
