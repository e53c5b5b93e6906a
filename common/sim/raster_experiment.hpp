#pragma once
// A raster scan on the simulated XY(Z) stage, in process and faster than real time: per axis the
// loop of a line-rate scan (sim/scan_experiment.hpp: the identified models, the stage's inverse,
// the servo), the axes coupled as a flexure stage couples them (x moves y by a few per cent), and
// the path given to every axis as its share of C^{-1} r (the decoupling) or, to show what the
// coupling does, of r alone. tests/sim/raster_test.cpp asserts the figures; bench/raster_table
// prints them and draws the error maps.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "sim/multi_axis_loop_simulation.hpp"
#include "sim/scan_experiment.hpp"

namespace hystloop {

struct RasterOptions {
  int axes = 2;                // 2 (XY) or 3 (XYZ: z holds its centre under the coupling of x and y)
  double width_m = 1e-6;       // fast axis (x), peak to peak
  double height_m = 1e-6;      // slow axis (y), first line to last
  int lines = 64;              //
  double line_rate_hz = 50.0;  // lines per second
  SlowMode slow_mode = SlowMode::kSteps;
  double coupling = 0.03;  // x -> y (and x, y -> z with three axes): flexure_stage()
  bool decouple = true;    // the shares of C^{-1} r; false: each axis its own reference
  bool learning = false;   // the fast axis learns from its lines
  ScanOptions loop{};      // per axis: servo, stage inverse, block size (its learning is `learning`)
};

struct RasterRun {
  bool refused = false;
  std::string reason;  // why it was refused
  RasterSpec raster;   // as run (its corners, its start)
  // Per axis, against the path's reference r (what the scan must draw, not the axis's share of
  // C^{-1} r) over the lines: every tick from line 0's start to the last line's end.
  std::array<TrackingStats, kScanAxes> stats{};
  // The same ticks for the error map: loop time and each axis's true-position error r - y.
  std::vector<double> t_s;
  std::array<std::vector<double>, kScanAxes> error_m;
  std::uint64_t clamped_ticks = 0;  // bridge ticks clamped (range or slew) on any axis, from the approach on
  std::uint64_t stage_trips = 0;
};

RasterRun run_raster(const TrackingExperiment& e, const IdentifiedModels& models, const RasterOptions& o);

}  // namespace hystloop
