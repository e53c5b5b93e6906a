#pragma once
// The tracking experiment of the MEM paper, on the simulated stage, in process and faster than
// real time: identify every model from the paper's identification input (250 V sin(20 pi t))
// run through the loop, then track y_d = -1.6 um cos(2 pi t) with a chosen feedforward, with or
// without feedback and online re-identification. tests/loop/tracking_test.cpp asserts its
// figures; bench/tracking_table.cpp prints them for docs/BENCHMARKS.md.

#include <cstdint>

#include "ident/mem_fit.hpp"
#include "loop/loop_simulation.hpp"

namespace hystloop {

struct TrackingExperiment {
  double identify_s = 2.0;  // length of the identification input [s]
  double track_s = 8.0;     // tracking run [s]
  double settle_s = 4.0;    // the error is measured over [settle_s, track_s)
  double noise_rms_m = 1e-9;
  std::uint64_t seed = 7;
  double kp = 0.1;          // feedback, when on (normalised, see loop/feedback.hpp)
  double ki = 600.0;        // [1/s]
};

struct IdentifiedModels {
  MemParams mem;
  MemFitResult mem_fit;
  PiParams pi;
  KatalenicParams katalenic;
  LinearParams linear;
  bool ok = false;  // every fit succeeded
};

struct TrackingRun {
  TrackingStats stats;
  std::int32_t params_version = 0;  // of the MEM set in use at the end
  MemParams final_mem{};
};

LoopSimulationConfig tracking_loop_config(const TrackingExperiment& e);

// Runs the identification input through the loop and fits MEM, PI-15, Katalenic and linear.
IdentifiedModels identify_models_through_loop(const TrackingExperiment& e);

// Tracks the MEM paper's reference with `mode`; MEM starts from `start_mem`. With reidentify,
// an online MEM estimator (4 s windows, 1 V reversal dead band) refits every second and offers
// accepted sets to the compensator.
TrackingRun run_tracking(const TrackingExperiment& e, const IdentifiedModels& models, FeedforwardMode mode,
                         bool feedback, bool reidentify, const MemParams& start_mem);

}  // namespace hystloop
