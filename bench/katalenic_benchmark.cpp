// Per-call cost of the Katalenic model (direct, eq. (2) with Lambert W) and its inverse (eq. (4)),
// with each shaping on input and output, on a 10 kHz sampled 10 Hz +-240 V sine (a reversal every
// 500 samples). p50/p99/max per call come from SampleTimer. Target: direct <= 300 ns.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstddef>
#include <vector>

#include "models/katalenic.hpp"
#include "models/katalenic_operator.hpp"
#include "sample_timing.hpp"

namespace {

using hystloop::KatalenicParams;
using hystloop::ShapingFunction;

KatalenicParams params_for(int shaping) {
  KatalenicParams p;  // piezo-like defaults, linear shaping
  if (shaping == 1) {
    p.input_shaping = ShapingFunction::make_odd_polynomial({1.0, 1e-6}, -300.0, 300.0);
    p.output_shaping = ShapingFunction::make_polynomial({0.0, 3.6e-9, 1.5e-12, 2e-15}, -300.0, 300.0);
  } else if (shaping == 2) {
    p.input_shaping = ShapingFunction::make_tanh(400.0, 500.0);
    p.output_shaping = ShapingFunction::make_tanh(1.2e-6, 450.0);
  }
  return p;
}

const char* shaping_name(int shaping) { return shaping == 0 ? "linear" : (shaping == 1 ? "polynomial" : "tanh"); }

std::vector<double> sine(double amplitude, double offset) {
  std::vector<double> s(1000);  // 10 Hz at 10 kHz
  for (std::size_t k = 0; k < s.size(); ++k)
    s[k] = offset + amplitude * std::sin(6.283185307179586 * static_cast<double>(k) / 1000.0);
  return s;
}

void BM_KatalenicForward(benchmark::State& state) {
  const int shaping = static_cast<int>(state.range(0));
  hystloop::KatalenicModel model(params_for(shaping));
  const auto u = sine(240.0, 0.0);
  model.reset(u[0]);
  hystloop::bench::time_per_sample(state, u, [&](double s) { return model.forward(s); });
  state.SetLabel(shaping_name(shaping));
}
BENCHMARK(BM_KatalenicForward)->Arg(0)->Arg(1)->Arg(2);

void BM_KatalenicInverse(benchmark::State& state) {
  const int shaping = static_cast<int>(state.range(0));
  const KatalenicParams p = params_for(shaping);
  // The reference spans the model's own output range for +-240 V.
  hystloop::KatalenicModel probe(p);
  probe.reset(0.0);
  const double lo = probe.forward(-240.0), hi = probe.forward(240.0);
  const auto y = sine(0.45 * (hi - lo), 0.5 * (hi + lo));
  hystloop::KatalenicInverse inverse(p);
  inverse.reset(y[0]);
  hystloop::bench::time_per_sample(state, y, [&](double s) { return inverse.inverse(s); });
  state.SetLabel(shaping_name(shaping));
}
BENCHMARK(BM_KatalenicInverse)->Arg(0)->Arg(1)->Arg(2);

void BM_KatalenicInverseWithRates(benchmark::State& state) {
  const KatalenicParams p = params_for(0);
  hystloop::KatalenicInverse inverse(p);
  const auto y = sine(0.7e-6, 0.0);
  inverse.reset(y[0]);
  hystloop::bench::SampleTimer timer;
  std::size_t i = 0;
  for (auto _ : state) {
    const double y_dot = 0.7e-6 * 62.83 * std::cos(6.283185307179586 * static_cast<double>(i) / 1000.0);
    timer.time([&] { benchmark::DoNotOptimize(inverse.inverse_with_rates(y[i], y_dot, 0.0)); });
    i = (i + 1 == y.size()) ? 0 : i + 1;
  }
  timer.report(state);
  state.SetLabel("linear");
}
BENCHMARK(BM_KatalenicInverseWithRates);

// The bare operator with a backlash-hard k2 (k1 k2 = 1000): Lambert W of e^s in the log domain
// right after each reversal.
void BM_KatalenicDirectOperatorLogDomain(benchmark::State& state) {
  hystloop::KatalenicDirectOperator op;
  const auto v = sine(5.0, 0.0);
  op.reset(v[0], v[0]);
  hystloop::bench::SampleTimer timer;
  std::size_t i = 0;
  for (auto _ : state) {
    timer.time([&] { benchmark::DoNotOptimize(op.apply(v[i], 1.0, 1000.0)); });
    i = (i + 1 == v.size()) ? 0 : i + 1;
  }
  timer.report(state);
}
BENCHMARK(BM_KatalenicDirectOperatorLogDomain);

}  // namespace
