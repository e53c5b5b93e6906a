// What several axes cost per tick, in process:
//   - the compensator's plan per tick (observe a sample, plan a tick) following a 25 Hz triangle
//     (a raster's fast line as a trajectory), and following a raster's share of the decoupled path
//     (ScanShare: the path evaluated per tick, the decoupling's term added), fast axis and slow
//     axis;
//   - a sensor block's encode and decode (what every LCM message costs its sender and each
//     receiver besides the syscalls): 10 ticks of one axis, of three axes in one block, and three
//     blocks of one axis each: what sharing one block saves.
// Means per tick (items_per_second); the machine is shared: compare within one run.
#include <benchmark/benchmark.h>

#include <array>
#include <cstdint>
#include <vector>

#include "lcm/blocks.hpp"
#include "lcm/message_storage.hpp"
#include "loop/compensator.hpp"
#include "loop/scan_path.hpp"

namespace {

using namespace hystloop;

constexpr std::int64_t kBatch = 1000;         // ticks per benchmark iteration
constexpr std::int64_t kRestartAt = 150'000;  // ticks before the path ends (900 lines at 50 Hz: 18 s)

RasterSpec long_raster() {
  RasterSpec r;
  r.width_m = 1e-6;
  r.height_m = 1e-6;
  r.lines = 900;
  r.line_rate_hz = 50.0;
  r.corner_s = 1.2e-3;
  r.start_s = 0.5;
  return r;
}

// 0: a 25 Hz triangle (TrajectorySpec); 1: the raster's fast axis as a share; 2: its slow axis,
// decoupled from a 3 % x -> y coupling.
Compensator prepared(int which) {
  CompensatorConfig c;
  c.horizon_ticks = 1;  // the plan follows the samples tick by tick
  // MEM with the tracking experiment's Ramberg-Osgood plant (6 nm/V at a reversal): the paper-like
  // default's small slope there would need more than the slew limit for a 50 Hz line.
  c.models.mem = MemParams{6.0e-9, 2.0e-12, 1.2};
  Compensator comp(c);
  comp.observe({0, 0.0, 0.0, 0.0});
  if (which == 0) {
    TrajectorySpec line = raster_fast_trajectory(long_raster());
    line.blend_s = 0.2;  // approached as the scans are
    comp.set_trajectory(line, 0.5);
  } else if (which == 1) {
    comp.take_scan(ScanShare(long_raster(), 0, AxisVector(1.0, 0.0, 0.0)), 0.2);
  } else {
    comp.take_scan(ScanShare(long_raster(), 1, AxisVector(-0.03, 1.0, 0.0)), 0.2);
  }
  return comp;
}

void BM_PlanTick(benchmark::State& state) {
  const Compensator prototype = prepared(static_cast<int>(state.range(0)));
  Compensator comp = prototype;
  std::vector<CommandTick> out(4);
  std::int64_t k = 1;
  double u = 0.0;
  for (auto _ : state) {
    for (std::int64_t end = k + kBatch; k < end; ++k) {
      comp.observe({k, u, 6.4e-9 * u, u});
      const std::size_t n = comp.plan(out);
      if (n > 0) u = out[n - 1].u_ff_V;
    }
    if (k >= kRestartAt) {
      state.PauseTiming();
      comp = prototype;
      k = 1;
      state.ResumeTiming();
    }
  }
  state.SetItemsProcessed(state.iterations() * kBatch);
  state.SetLabel(state.range(0) == 0   ? "triangle trajectory"
                 : state.range(0) == 1 ? "raster fast axis (scan share)"
                                       : "raster slow axis, decoupled");
}
BENCHMARK(BM_PlanTick)->Arg(0)->Arg(1)->Arg(2);

sensor_block_t block_of(int axes) {
  sensor_block_t b{};
  reserve_storage(b);
  begin_block(b, 1000, 1'700'000'000'000'000, 1e-4, axes);
  for (std::int64_t k = 1000; k < 1010; ++k) {
    std::array<SensorTick, 3> t{};
    for (int a = 0; a < axes; ++a) {
      t[static_cast<std::size_t>(a)] = SensorTick{0, k, 1.0 + a, 0.9, 0.1, 1e-6, 1.1e-6, 4};
    }
    append_tick(b, std::span<const SensorTick>(t.data(), static_cast<std::size_t>(axes)));
  }
  return b;
}

// range(0): axes per block; range(1): blocks per 10 ticks (3 x 1 axis: the alternative to sharing).
void BM_SensorBlockEncodeDecode(benchmark::State& state) {
  const auto axes = static_cast<int>(state.range(0));
  const auto blocks = static_cast<int>(state.range(1));
  const sensor_block_t sent = block_of(axes);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(sent.getEncodedSize()));
  sensor_block_t got{};
  reserve_storage(got);
  for (auto _ : state) {
    for (int i = 0; i < blocks; ++i) {
      sent.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
      clear_arrays(got);
      benchmark::DoNotOptimize(got.decode(bytes.data(), 0, static_cast<int>(bytes.size())));
    }
  }
  state.SetItemsProcessed(state.iterations() * 10);  // ticks of the stage (every axis)
  state.SetLabel(std::to_string(blocks) + " block(s) of " + std::to_string(axes) + " axis/axes per 10 ticks");
}
BENCHMARK(BM_SensorBlockEncodeDecode)->Args({1, 1})->Args({3, 1})->Args({1, 3});

}  // namespace
