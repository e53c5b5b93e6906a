// The comedi backend's per-tick bookkeeping (bridge.backend: comedi): the clamp and conversion
// of the tick's voltage to a DAC code, the instruction list, the conversion of the ADC code to
// metres, the fault check and the counters. Against the fake card (tests/hw/fake_comedi.hpp):
// its comedi_do_insnlist only copies two words, where the real one is an ioctl into the card's
// driver (a register write and a conversion, typically several microseconds on a PCI/PCIe card):
// that part is the card's and is measured on the lab's machine with the card (HX_STATUS loop_*,
// --summary-json), not here.
#include <benchmark/benchmark.h>
#include <spdlog/spdlog.h>

#include "bridge/comedi_backend.hpp"
#include "fake_comedi.hpp"

namespace hystloop {
namespace {

ComediSettings bench_settings() {
  ComediSettings c;
  c.ao = {1, 0, 0, AREF_GROUND};
  c.ai = {0, 0, 1, AREF_DIFF};
  return c;
}

void run_steps(benchmark::State& state, bool softcal) {
  spdlog::set_level(spdlog::level::warn);  // the backend's start-up line, once per run
  fake_comedi::reset();
  fake_comedi::state().calibration = softcal;
  fake_comedi::state().mirror_gain = 0.4;
  ComediBackend backend(bench_settings(), ActuatorLimits{});
  for (int i = 0; i < (1 << 18); ++i) backend.step(0.0, 0, 1e-4);  // fill the fake's record: no more copies
  double u = 0.0;
  for (auto _ : state) {
    u = u > 200.0 ? -200.0 : u + 0.37;
    benchmark::DoNotOptimize(backend.step(u, 0.0, 1e-4));
  }
}

void BM_ComediStepRangeTables(benchmark::State& state) { run_steps(state, false); }
void BM_ComediStepSoftcal(benchmark::State& state) { run_steps(state, true); }

// The conversions alone, without the (fake) transfer.
void BM_ComediConvertOnly(benchmark::State& state) {
  spdlog::set_level(spdlog::level::warn);
  fake_comedi::reset();
  ComediBackend backend(bench_settings(), ActuatorLimits{});
  double u = 0.0;
  lsampl_t counts = 1000;
  for (auto _ : state) {
    u = u > 200.0 ? -200.0 : u + 0.37;
    counts = counts > 60000 ? 1000 : counts + 7;
    benchmark::DoNotOptimize(backend.dac_code(u));
    benchmark::DoNotOptimize(backend.position_m(counts));
  }
}

BENCHMARK(BM_ComediStepRangeTables);
BENCHMARK(BM_ComediStepSoftcal);
BENCHMARK(BM_ComediConvertOnly);

}  // namespace
}  // namespace hystloop
