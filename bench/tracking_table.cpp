// tracking_table: the tracking figures of docs/BENCHMARKS.md, as tests/loop/tracking_test.cpp
// computes them, printed as a Markdown table beside the MEM paper's measured figures.
//
// In process and faster than real time (common/loop/loop_simulation.hpp): the Banning stage
// (Tables 1-2, 1 nm RMS sensor noise, seed 7), every model identified from the MEM paper's
// identification experiment (250 V sin(20 pi t), 2 s) run through the loop, then the reference
// y_d = -1.6 um cos(2 pi t) tracked with each feedforward, without and with PI feedback
// (kp 0.1, ki 600 1/s); RMS error over t in [4, 8) s against the true position.
//
//   tracking_table            prints the table (Markdown) and the identified MEM parameters

#include <chrono>
#include <cstdio>

#include "loop/tracking_experiment.hpp"

int main() {
  using namespace hystloop;
  const auto t0 = std::chrono::steady_clock::now();
  const TrackingExperiment experiment;
  const IdentifiedModels id = identify_models_through_loop(experiment);
  std::printf("Identified MEM: c1 = %.4g m/V, c2 = %.4g, c3 = %.4g (fit residual %.2f nm)\n\n", id.mem.c1, id.mem.c2,
              id.mem.c3, id.mem_fit.residual_rms_m * 1e9);
  MemParams wrong = id.mem;
  wrong.c1 *= 0.6;
  wrong.c2 *= 1.8;
  struct Row {
    const char* name;
    FeedforwardMode mode;
    bool reid;
    bool wrong_start;
    const char* paper;  // the MEM paper's measurement on its real actuator, feedforward only
  };
  const Row rows[] = {{"linear", FeedforwardMode::kLinear, false, false, "339.3 nm"},
                      {"PI-15", FeedforwardMode::kPi, false, false, "97.5 nm"},
                      {"Katalenic", FeedforwardMode::kKatalenic, false, false, "—"},
                      {"MEM", FeedforwardMode::kMem, false, false, "27.9 nm"},
                      {"MEM, wrong parameters (c1 × 0.6, c2 × 1.8)", FeedforwardMode::kMem, false, true, "—"},
                      {"MEM, wrong + online re-identification", FeedforwardMode::kMem, true, true, "—"}};
  std::printf("| feedforward | simulation: feedforward only (true / measured) | simulation: + PI feedback (true / measured) "
              "| MEM paper, real actuator, feedforward only |\n| --- | --- | --- | --- |\n");
  for (const Row& r : rows) {
    const MemParams& start = r.wrong_start ? wrong : id.mem;
    const TrackingStats ff = run_tracking(experiment, id, r.mode, false, r.reid, start).stats;
    const TrackingStats fb = run_tracking(experiment, id, r.mode, true, r.reid, start).stats;
    std::printf("| %s | %.2f / %.2f nm | %.2f / %.2f nm | %s |\n", r.name, ff.rms_true_m * 1e9, ff.rms_measured_m * 1e9,
                fb.rms_true_m * 1e9, fb.rms_measured_m * 1e9, r.paper);
    std::fflush(stdout);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("\n(%.0f s of simulated loop at 10 kHz in %.1f s of wall time)\n",
              experiment.identify_s + 12 * experiment.track_s, seconds);
  return id.ok ? 0 : 1;
}
