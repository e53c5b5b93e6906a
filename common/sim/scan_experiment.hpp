#pragma once
// Scans at line rate on the simulated stage, in process and faster than real time: the references
// a lab runs (raster lines: rounded triangles; sines) at 10-200 Hz, tracked with the models
// identified through the loop (sim/tracking_experiment.hpp), with or without the stage's inverse,
// the servo and learning. tests/sim/scan_test.cpp asserts the figures; bench/tracking_table
// prints them for docs/TRACKING.md, and deploy/hystloop scan runs the same references live.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sim/tracking_experiment.hpp"

namespace hystloop {

struct ScanReference {
  std::string name;  // "triangle 50 Hz 1 um"
  TrajectoryShape shape = TrajectoryShape::kSine;
  double amplitude_m = 1e-6;
  double frequency_hz = 10.0;
};

// The line-rate targets: triangles of 1 um at 10 and 50 Hz, sines of 1 um at 10 and 50 Hz,
// 0.5 um at 100 Hz and 0.25 um at 200 Hz.
std::vector<ScanReference> scan_references();

// The models for a scan of this amplitude: identified from a 10 Hz sine (2 s) through the loop
// making the loops the line will make, 160 V per um of amplitude (the MEM paper's 250 V input
// fits the major loop, whose slopes near a reversal are not those of a 1 um loop: PI-15 tracks a
// 10 Hz, 1 um sine at 1.2 nm fitted there, at 0.55 nm fitted here). Online, the re-identifier's
// model choice refits on the line's own data, which is what this stands for.
// With `removed` (scan_stage(): the stage the scan's compensator inverts), the hysteresis is
// fitted on the samples with that stage taken out (identify_models_through_loop).
IdentifiedModels identify_for_scan(const TrackingExperiment& e, double amplitude_m, const StageModel& removed = {});

struct ScanOptions {
  std::optional<FeedforwardMode> mode;  // nullopt: the identification's best (hystloop-identify --model auto)
  bool stage_inverse = true;  // Banning's k, c (a series plant: its linear stage) inverted beside the hysteresis
  std::optional<LinearStageSpec> stage_model;  // a series plant: the stage model inverted (nullopt: the plant's own)
  double stage_known_to_hz = 0.0;  // ... and how far up its identification measured it (StageModel::known_to_hz)
  bool servo = true;               // the bridge's servo as deploy/config/bridge.yaml sets it:
  double kp = 0.05, ki = 2000.0, notch_hz = 1720.0, notch_q = 0.7;  // PI [-, 1/s], notch [Hz, -]
  double notch2_hz = 0.0, notch2_q = 2.0;                           // a second notch [Hz, -]; 0 = none
  bool learning = false;
  // A line outside the actuator's limits (the servo's reserve included) is scaled to fit, as
  // deploy/hystloop scan asks (scan.yaml if_infeasible: shape); false: refused.
  bool shape_if_infeasible = true;
  double servo_slew_reserve = CompensatorConfig{}.servo_slew_reserve;  // of the slew limit, kept for the servo
  int block_ticks = LoopSimulationConfig{}.block_ticks;                // samples per sensor block
  int settle_periods = 20;     // the error is measured after these whole periods ...
  int measure_periods = 10;    // ... over these
  double min_measure_s = 0.2;  // at least this long (more periods at high rates)
};

struct ScanRun {
  bool refused = false;      // the compensator refused the reference (reason says why)
  std::string reason;        // or how it was taken (the corner chosen, the shaping)
  bool shaped = false;       // the amplitude was scaled to fit the limits ...
  double amplitude_m = 0.0;  // ... to this (the reference's own when not shaped)
  double corner_s = 0.0;
  TrackingStats stats;                   // over the measured periods
  std::vector<double> rms_per_period_m;  // true-position RMS of every whole period from the start
  std::uint64_t clamped_ticks = 0;       // ticks the bridge clamped (range or slew), from the start
  int periods_to_converge = -1;          // first period from which every period is <= 1 nm RMS (-1: never)
  CompensatorCounters counters{};
  FeedforwardMode mode = FeedforwardMode::kOff;  // the model used
};

// The stage the scan's compensator inverts beside the hysteresis (kind none without
// o.stage_inverse): Banning's second order on the Banning plant, the series plant's linear stage
// (o.stage_model when given) on a series plant.
StageModel scan_stage(const TrackingExperiment& e, const ScanOptions& o);

// The loop run_scan runs: the models (o.mode or the ranking's best), the stage's inverse, learning,
// the servo and the block size as `o` asks.
LoopSimulationConfig scan_loop_config(const TrackingExperiment& e, const IdentifiedModels& models,
                                      const ScanOptions& o);

ScanRun run_scan(const TrackingExperiment& e, const IdentifiedModels& models, const ScanReference& r,
                 const ScanOptions& o);

}  // namespace hystloop
