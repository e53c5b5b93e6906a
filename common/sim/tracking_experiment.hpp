#pragma once
// The tracking experiment of the MEM paper, on the simulated stage, in process and faster than
// real time: identify every model from the paper's identification input (250 V sin(20 pi t))
// run through the loop, then track y_d = -1.6 um cos(2 pi t) with a chosen feedforward, with or
// without feedback and online re-identification (the MEM estimator alone, or the online model
// selector, free or pinned). tests/sim/tracking_test.cpp asserts its figures;
// bench/tracking_table.cpp prints them for docs/BENCHMARKS.md and docs/TRACKING.md.

#include <cstdint>
#include <vector>

#include "ident/mem_fit.hpp"
#include "ident/online_model_selector.hpp"
#include "sim/loop_simulation.hpp"

namespace hystloop {

struct TrackingExperiment {
  double identify_s = 2.0;  // length of the identification input [s]
  double track_s = 8.0;     // tracking run [s]
  double settle_s = 4.0;    // the error is measured over [settle_s, track_s)
  double noise_rms_m = 1e-9;
  std::uint64_t seed = 7;
  double kp = 0.1;    // feedback, when on (normalised, see loop/feedback.hpp)
  double ki = 600.0;  // [1/s]
  PlantKind plant = PlantKind::kBanning;
  // The Ramberg-Osgood plant's truth. Not paper_like(): its +-250 V major loop spans 3.17 um, less
  // than the reference's 3.2 um, so the actuator's range would clip the feedforward. These span
  // 3.79 um at +-250 V (the reference needs about +-215 V).
  MemParams ramberg_osgood{6.0e-9, 2.0e-12, 1.2};
  // Gain drift of the stage during tracking only (identification sees the stage as it was):
  // +drift_fraction over drift_duration_s from the start of the tracking run.
  double drift_fraction = 0.0;
  double drift_duration_s = 30.0;
  // The series plant's (plant kSeries): its hysteresis, then its linear stage with delay.
  HysteresisPlantSpec series_hysteresis{};
  LinearStageSpec series_stage = SimulatedStageConfig{}.linear;
};

// A typical lab stage under a load: Banning's Table 1 hysteresis, then two lightly damped modes
// (780 Hz, zeta 0.03, 92 % of the DC gain; 2.4 kHz, zeta 0.02, 8 %) and 1.5 ticks of I/O delay.
TrackingExperiment two_mode_experiment();

struct IdentifiedModels {
  MemParams mem;
  MemFitResult mem_fit;
  PiParams pi;
  KatalenicParams katalenic;
  LinearParams linear;
  bool ok = false;  // every fit succeeded
  // The candidates ranked on the record's held-out branches, as hystloop-identify --model auto.
  std::vector<ModelKind> ranking;
};

enum class Reidentify : std::uint8_t {
  off,
  mem,     // OnlineMemEstimator refits MEM, offer_mem_params (the MEM paper's workflow)
  select,  // propose_model on the estimator's window, offer_model (model change unless pinned)
};

struct TrackingOptions {
  FeedforwardMode mode = FeedforwardMode::kMem;
  bool feedback = false;
  Reidentify reidentify = Reidentify::off;
  MemParams start_mem{};       // MEM's parameters at the start
  double refit_every_s = 1.0;  // re-identification period [s]
  double window_s = 4.0;       // the estimator's window [s] (4 s: eight branches of the 1 Hz reference)
  // With Reidentify::select (pinned: no model change). Fits at 2 kHz: 10 kHz / 5 keeps MEM's c2 within
  // 0.4 % on the Ramberg-Osgood stage (10 kHz / 10: 1.2 %) at a fifth of the fitting time.
  OnlineSelectorOptions selector{.decimation = 5};
};

// A parameter swap as the bridge applied it (the first tick with a new params_version).
struct SwapRecord {
  double t_s = 0.0;
  std::int32_t version = 0;
  double rms_before_m = 0.0;  // true-position RMS over the 5 s before the swap (or what there is)
  double rms_after_m = 0.0;   // ... and the 5 s after
  bool worse = false;         // after > (1 + margin) x before
};

struct TrackingRun {
  TrackingStats stats;
  std::int32_t params_version = 0;  // of the set in use at the end
  MemParams final_mem{};
  ModelKind final_kind = ModelKind::mem;
  FeedforwardMode final_mode = FeedforwardMode::kMem;
  std::vector<double> rms_per_second_m;  // true-position RMS over [i, i + 1) s (0: no reference)
  std::vector<SwapRecord> swaps;
  int worse_swaps = 0;              // swaps with `worse`
  int offers_refused = 0;           // offers the compensator refused (goal: 0)
  double first_kind_time_s = -1.0;  // when the last model switch was planned (-1: none)
  CompensatorCounters counters{};
};

LoopSimulationConfig tracking_loop_config(const TrackingExperiment& e);
// The loop's compensator with these models (MEM's as given) and the bridge's actuator limits.
void use_models(LoopSimulationConfig& c, const IdentifiedModels& models, const MemParams& mem);

// Runs the identification input through the loop and fits MEM, PI-15, Katalenic and linear.
IdentifiedModels identify_models_through_loop(const TrackingExperiment& e);
// The same with another excitation (its duration_s is the record's length), e.g. one sized to
// the loops a scan will make. With a stage that has dynamics (removed), the hysteresis is fitted
// on the samples with that stage taken out (ident/stage_removal.hpp), as a compensator that
// inverts that stage needs: fitted u -> y, the hysteresis would carry the stage's lag and delay as
// width, which the compensator would then correct on top of the stage's own inverse.
IdentifiedModels identify_models_through_loop(const TrackingExperiment& e, const ExperimentSpec& input,
                                              const StageModel& removed = {});

// Tracks the MEM paper's reference for e.track_s; the error is measured over [e.settle_s, e.track_s).
TrackingRun run_tracking(const TrackingExperiment& e, const IdentifiedModels& models, const TrackingOptions& options);

// The original form: `reidentify` is Reidentify::mem (an online MEM estimator, 4 s windows,
// 1 V reversal dead band, refitting every second).
TrackingRun run_tracking(const TrackingExperiment& e, const IdentifiedModels& models, FeedforwardMode mode,
                         bool feedback, bool reidentify, const MemParams& start_mem);

}  // namespace hystloop
