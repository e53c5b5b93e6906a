#pragma once
// Paths on the simulated XY(Z) stage, in process and faster than real time: a raster (the fast
// axis's lines, the slow axis stepping) or a Lissajous figure (each axis a sine of its own
// frequency). Per axis the loop of a line-rate scan (sim/scan_experiment.hpp: the identified
// models, the stage's inverse, the servo), the axes coupled as a flexure stage couples them (x
// moves y by a few per cent), and the path given to every axis as its share of C^{-1} r (the
// decoupling) or, to show what the coupling does, of r alone. tests/sim/raster_test.cpp asserts
// the figures; bench/raster_table prints them and draws the error maps.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ident/coupling_fit.hpp"
#include "sim/multi_axis_loop_simulation.hpp"
#include "sim/scan_experiment.hpp"

namespace hystloop {

// The stage and the loops around it.
struct PathLoopOptions {
  int axes = 2;            // 2 (XY) or 3 (XYZ: z holds its centre under the coupling of x and y)
  double coupling = 0.03;  // x -> y (and x, y -> z with three axes): flexure_stage()
  bool decouple = true;    // the shares of C^{-1} r; false: each axis its own reference
  // Decouple with the coupling identified on the stage first (identify_coupling), as a lab must,
  // instead of the simulated stage's true one.
  bool identified_decoupling = false;
  bool learning = false;  // a raster's fast axis learns from its lines
  ScanOptions loop{};     // per axis: servo, stage inverse, block size (its learning is `learning`)
};

struct RasterOptions : PathLoopOptions {
  double width_m = 1e-6;       // fast axis (x), peak to peak
  double height_m = 1e-6;      // slow axis (y), first line to last
  int lines = 64;              //
  double line_rate_hz = 50.0;  // lines per second
  SlowMode slow_mode = SlowMode::kSteps;
};

// Each axis a sine entered at its trough (at rest), whole periods of every axis over duration_s.
struct LissajousOptions : PathLoopOptions {
  std::array<double, kScanAxes> amplitude_m{0.5e-6, 0.5e-6, 0.0};
  std::array<double, kScanAxes> frequency_hz{50.0, 48.0, 1.0};
  double duration_s = 1.0;
};

struct PathRun {
  bool refused = false;
  std::string reason;  // why it was refused
  // Per axis, against the path's reference r (what the path must draw, not the axis's share of
  // C^{-1} r) over the path: every tick from its start to its end (a raster's last line).
  std::array<TrackingStats, kScanAxes> stats{};
  // The same ticks for an error map: loop time and each axis's true-position error r - y.
  std::vector<double> t_s;
  std::array<std::vector<double>, kScanAxes> error_m;
  std::uint64_t clamped_ticks = 0;  // bridge ticks clamped (range or slew) on any axis, from the approach on
  std::uint64_t stage_trips = 0;
  // With identified_decoupling: the identification the decoupling used (refused: the run is too).
  std::optional<CouplingFitResult> coupling_fit;
};

struct RasterRun : PathRun {
  RasterSpec raster;  // as run (its corners, its start)
};

struct LissajousRun : PathRun {
  LissajousSpec figure;  // as run
};

// The coupling experiment a lab runs on the stage: each axis in turn driven by a sine of
// `amplitude_V` at 5 Hz (four periods, the compensator's identification experiment) with every
// servo off (a servo would hold the other axes against the very coupling to be measured) and
// the other axes holding, every sensor recorded, one second between experiments for the axis
// just excited to come back to rest; fit_coupling on the records.
CouplingFitResult identify_coupling(const TrackingExperiment& e, const IdentifiedModels& models,
                                    const PathLoopOptions& o, double amplitude_V = 100.0);

RasterRun run_raster(const TrackingExperiment& e, const IdentifiedModels& models, const RasterOptions& o);
LissajousRun run_lissajous(const TrackingExperiment& e, const IdentifiedModels& models, const LissajousOptions& o);

}  // namespace hystloop
