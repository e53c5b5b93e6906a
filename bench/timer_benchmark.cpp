// Cost of the timing bookkeeping a 10 kHz loop does every tick: recording one
// latency, the deadline arithmetic, and (once a second) reading percentiles.
#include <benchmark/benchmark.h>

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
