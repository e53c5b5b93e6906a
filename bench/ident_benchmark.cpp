// Identification figures: MEM fit of 2 s at 10 kHz (target <= 20 ms median), the online
// estimator's per-sample feed (target <= 50 ns) and a refit, the Banning recipe end to end.
//   ./build/bench/ident_benchmark --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "ident/banning_experiments.hpp"
#include "ident/banning_fit.hpp"
#include "ident/mem_fit.hpp"
#include "ident/online_mem_estimator.hpp"
#include "models/mem.hpp"
#include "sample_timing.hpp"

namespace {

using namespace hystloop;

struct MemRecord {
  std::vector<double> u, y;
};

// The paper's identification experiment on the project's MEM model, 1 nm RMS sensor noise.
const MemRecord& paper_record() {
  static const MemRecord rec = [] {
    MemRecord r;
    MemModel model(MemParams::paper_like());
    model.reset(0.0);
    std::mt19937_64 rng(1);
    std::normal_distribution<double> noise(0.0, 1e-9);
    for (int k = 0; k < 20000; ++k) {
      const double u = 250.0 * std::sin(2.0 * std::numbers::pi * 10.0 * k * 1e-4);
      r.u.push_back(u);
      r.y.push_back(model.forward(u) + noise(rng));
    }
    return r;
  }();
  return rec;
}

void mem_fit(benchmark::State& state, MemFitForm form, bool refine) {
  const MemRecord& rec = paper_record();
  MemFitOptions o;
  o.form = form;
  o.refine_with_ceres = refine;
  hystloop::bench::SampleTimer timer(1 << 12);
  for (auto _ : state) {
    timer.time([&] {
      MemFitResult r = fit_mem(rec.u, rec.y, o);
      benchmark::DoNotOptimize(r);
      if (!r.ok()) state.SkipWithError(r.reason.c_str());
    });
  }
  timer.report(state);
  state.counters["samples"] = static_cast<double>(rec.u.size());
}
void BM_MemFit_Integrated_20k(benchmark::State& s) { mem_fit(s, MemFitForm::integrated, true); }
void BM_MemFit_Integrated_ProjectionOnly_20k(benchmark::State& s) { mem_fit(s, MemFitForm::integrated, false); }
void BM_MemFit_Derivative_20k(benchmark::State& s) { mem_fit(s, MemFitForm::derivative, true); }
BENCHMARK(BM_MemFit_Integrated_20k)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_MemFit_Integrated_ProjectionOnly_20k)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_MemFit_Derivative_20k)->Unit(benchmark::kMillisecond)->MinTime(1.0);

// One feed() per iteration: the benchmark's time/iteration is the per-sample cost; the p50/p99
// counters time single calls and include ~20 ns of clock reads.
void BM_OnlineFeed(benchmark::State& state) {
  const MemRecord& rec = paper_record();
  OnlineMemEstimator est({}, MemParams::paper_like());
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(est.feed(rec.u[k], rec.y[k]));
    if (++k == rec.u.size()) k = 0;
  }
}
BENCHMARK(BM_OnlineFeed);

void BM_OnlineFeed_Percentiles(benchmark::State& state) {
  const MemRecord& rec = paper_record();
  OnlineMemEstimator est({}, MemParams::paper_like());
  hystloop::bench::SampleTimer timer;
  std::size_t k = 0;
  for (auto _ : state) {
    timer.time([&] { benchmark::DoNotOptimize(est.feed(rec.u[k], rec.y[k])); });
    if (++k == rec.u.size()) k = 0;
  }
  timer.report(state);
}
BENCHMARK(BM_OnlineFeed_Percentiles);

// snapshot (2 s window) + evaluate: the refit the re-identifier runs off the hot path.
void BM_OnlineRefit(benchmark::State& state) {
  const MemRecord& rec = paper_record();
  MemParams in_use = MemParams::paper_like();
  in_use.c1 *= 0.9;
  OnlineMemEstimator est({}, in_use);
  for (std::size_t k = 0; k < rec.u.size(); ++k) est.feed(rec.u[k], rec.y[k]);
  MemWindow w = est.make_window();
  hystloop::bench::SampleTimer timer(1 << 12);
  for (auto _ : state) {
    timer.time([&] {
      est.snapshot(w);
      MemRefitOutcome r = OnlineMemEstimator::evaluate(w, est.params(), est.version(), est.options());
      benchmark::DoNotOptimize(r);
    });
  }
  timer.report(state);
}
BENCHMARK(BM_OnlineRefit)->Unit(benchmark::kMillisecond)->MinTime(1.0);

// Banning: plan, simulate on the stage (Tables 1-2, 1 nm noise), fit. And the fit alone.
struct BanningRecord {
  std::vector<BanningExperiment> plan;
  std::vector<std::vector<double>> y;
  std::vector<BanningExperimentData> data;
};
BanningRecord record_banning() {
  BanningRecord r;
  r.plan = plan_banning_experiments();
  for (std::size_t i = 0; i < r.plan.size(); ++i) r.y.push_back(run_on_stage(BanningStageParams{}, r.plan[i], 1e-9, i));
  for (std::size_t i = 0; i < r.plan.size(); ++i) {
    const std::size_t m = r.plan[i].measure_begin;
    r.data.push_back({std::span(r.plan[i].u).subspan(m), std::span(r.y[i]).subspan(m), r.plan[i].sample_rate_Hz});
  }
  return r;
}

void BM_BanningRecipe_EndToEnd(benchmark::State& state) {
  std::size_t samples = 0;
  for (auto _ : state) {
    const BanningRecord r = record_banning();
    BanningFitResult f = fit_banning(r.data);
    if (!f.ok()) state.SkipWithError(f.reason.c_str());
    benchmark::DoNotOptimize(f);
    samples = 0;
    for (const auto& e : r.plan) samples += e.u.size();
  }
  state.counters["samples_simulated"] = static_cast<double>(samples);
}
BENCHMARK(BM_BanningRecipe_EndToEnd)->Unit(benchmark::kMillisecond);

void BM_BanningRecipe_FitOnly(benchmark::State& state) {
  const BanningRecord r = record_banning();
  for (auto _ : state) {
    BanningFitResult f = fit_banning(r.data);
    benchmark::DoNotOptimize(f);
  }
}
BENCHMARK(BM_BanningRecipe_FitOnly)->Unit(benchmark::kMillisecond);

}  // namespace
