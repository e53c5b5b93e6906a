// Per-call cost of the simulated stage at the bridge's 10 kHz (dt = 100 us): BanningStage::step
// (target <= 1 us), the Coleman–Hodgdon step alone and the second-order stage alone. The input is
// a 2 Hz, 200 V sine plus a 1 kHz ripple, so reversals (and, in the paper's order, the Hermite
// extreme search) are exercised. SampleTimer adds p50/p99/p999/max per call.

#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "sample_timing.hpp"
#include "models/banning_stage.hpp"
#include "models/coleman_hodgdon.hpp"
#include "models/second_order_stage.hpp"

namespace {

using hystloop::bench::SampleTimer;

constexpr double kDt = 100e-6;

std::vector<double> input_signal() {
  std::vector<double> u(100000);  // 10 s at 10 kHz
  for (std::size_t i = 0; i < u.size(); ++i) {
    const double t = static_cast<double>(i) * kDt;
    u[i] = 200.0 * std::sin(2.0 * std::numbers::pi * 2.0 * t) + 5.0 * std::sin(2.0 * std::numbers::pi * 1000.0 * t);
  }
  return u;
}

void BM_BanningStageStep(benchmark::State& state) {
  hystloop::BanningStageParams p;
  p.order =
      state.range(0) == 0 ? hystloop::BanningOrder::kHysteresisThenStage : hystloop::BanningOrder::kStageThenHysteresis;
  hystloop::BanningStage stage(p);
  const std::vector<double> u = input_signal();
  SampleTimer timer;
  std::size_t i = 0;
  for (auto _ : state) {
    timer.time([&] { benchmark::DoNotOptimize(stage.step(u[i], kDt)); });
    i = i + 1 == u.size() ? 0 : i + 1;
  }
  timer.report(state);
  state.SetLabel(state.range(0) == 0 ? "CH then stage (default)" : "stage then CH (paper)");
}
BENCHMARK(BM_BanningStageStep)->Arg(0)->Arg(1);

void BM_ColemanHodgdonStep(benchmark::State& state) {
  hystloop::ColemanHodgdon ch;
  const std::vector<double> u = input_signal();
  SampleTimer timer;
  std::size_t i = 0;
  for (auto _ : state) {
    timer.time([&] { benchmark::DoNotOptimize(ch.step(u[i])); });
    i = i + 1 == u.size() ? 0 : i + 1;
  }
  timer.report(state);
}
BENCHMARK(BM_ColemanHodgdonStep);

void BM_SecondOrderStageStep(benchmark::State& state) {
  hystloop::SecondOrderStage stage;
  const std::vector<double> u = input_signal();
  SampleTimer timer;
  std::size_t i = 0;
  for (auto _ : state) {
    timer.time([&] { benchmark::DoNotOptimize(stage.step(8.58e-9 * u[i], kDt)); });
    i = i + 1 == u.size() ? 0 : i + 1;
  }
  timer.report(state);
}
BENCHMARK(BM_SecondOrderStageStep);

}  // namespace
