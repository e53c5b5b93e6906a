// The whole control law on the Banning stage (Tables 1-2, 1 nm sensor noise), in process and
// faster than real time: identify every model from the MEM paper's identification experiment
// (250 V sin(20 pi t)) run through the loop, then track the MEM paper's reference (24)
// y_d = -1.6 um cos(2 pi t) with each feedforward, with and without feedback, and with online
// re-identification from deliberately wrong MEM parameters. Prints the table; asserts the
// figures the product promises.

#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "loop/tracking_experiment.hpp"

namespace hystloop {
namespace {

using TrackRun = TrackingRun;

const TrackingExperiment kExperiment{};
constexpr double kSettleSeconds = TrackingExperiment{}.settle_s;
constexpr double kTrackSeconds = TrackingExperiment{}.track_s;

const IdentifiedModels& identified() {
  static const IdentifiedModels models = [] {
    IdentifiedModels m = identify_models_through_loop(kExperiment);
    EXPECT_TRUE(m.ok) << "MEM: " << m.mem_fit.reason;
    std::printf("identified MEM c1=%.4g m/V c2=%.4g c3=%.4g (residual %.2f nm)\n", m.mem.c1, m.mem.c2, m.mem.c3,
                m.mem_fit.residual_rms_m * 1e9);
    return m;
  }();
  return models;
}

TrackRun track(FeedforwardMode mode, bool feedback, bool reidentify, const MemParams* start_mem = nullptr) {
  return run_tracking(kExperiment, identified(), mode, feedback, reidentify, start_mem ? *start_mem : identified().mem);
}

// Deliberately wrong MEM parameters for the re-identification runs: the demo's starting point.
MemParams wrong_mem() {
  MemParams m = identified().mem;
  m.c1 *= 0.6;
  m.c2 *= 1.8;
  return m;
}

TEST(Tracking, EveryModeOnTheBanningStage) {
  struct Row {
    std::string name;
    FeedforwardMode mode;
    bool reid;
    bool wrong_start;
  };
  const std::vector<Row> rows = {{"linear", FeedforwardMode::kLinear, false, false},
                                 {"PI-15", FeedforwardMode::kPi, false, false},
                                 {"Katalenic", FeedforwardMode::kKatalenic, false, false},
                                 {"MEM", FeedforwardMode::kMem, false, false},
                                 {"MEM, wrong parameters", FeedforwardMode::kMem, false, true},
                                 {"MEM, wrong + re-ident.", FeedforwardMode::kMem, true, true}};
  std::printf("\nRMS tracking error of y_d = -1.6 um cos(2 pi t), t in [%.0f, %.0f) s, true / measured position\n",
              kSettleSeconds, kTrackSeconds);
  std::printf("%-24s %24s %24s\n", "feedforward", "feedforward only", "+ PI feedback");
  std::map<std::string, std::pair<TrackRun, TrackRun>> table;
  const MemParams wrong = wrong_mem();
  for (const Row& r : rows) {
    const MemParams* start = r.wrong_start ? &wrong : nullptr;
    const TrackRun ff = track(r.mode, false, r.reid, start);
    const TrackRun fb = track(r.mode, true, r.reid, start);
    table[r.name] = {ff, fb};
    std::printf("%-24s %10.2f / %7.2f nm %10.2f / %7.2f nm\n", r.name.c_str(), ff.stats.rms_true_m * 1e9,
                ff.stats.rms_measured_m * 1e9, fb.stats.rms_true_m * 1e9, fb.stats.rms_measured_m * 1e9);
  }
  // With feedback every mode reaches a few nanometres (the sensor noise is 1 nm RMS).
  for (const auto& [name, runs] : table) {
    EXPECT_LE(runs.second.stats.rms_true_m, 5e-9) << name << " with feedback";
  }
  // Feedforward alone: the ordering and magnitudes an independent simulation of this stage found
  // (linear 115-140 nm, MEM 25-55 nm, Katalenic 5-6 nm, PI-15 2-3 nm), with margins.
  EXPECT_GT(table["linear"].first.stats.rms_true_m, 80e-9);
  EXPECT_LT(table["linear"].first.stats.rms_true_m, 200e-9);
  EXPECT_LT(table["MEM"].first.stats.rms_true_m, 60e-9);
  EXPECT_LT(table["MEM"].first.stats.rms_true_m, 0.5 * table["linear"].first.stats.rms_true_m);
  EXPECT_LT(table["Katalenic"].first.stats.rms_true_m, 10e-9);
  EXPECT_LT(table["PI-15"].first.stats.rms_true_m, 10e-9);
  // Re-identification repairs wrong parameters: it swaps new sets in, they approach what the
  // offline fit found (the best MEM element for this stage), and with feedback the loop beats
  // the MEM paper's 27.9 nm widely. Feedforward alone keeps the loop offset that the wrong
  // parameters created: the MEM element remembers only its last branching point, so better
  // parameters fix the loop's shape but not where it sits (see docs/TRACKING.md).
  const auto& reid = table["MEM, wrong + re-ident."];
  for (const TrackRun* r : {&reid.first, &reid.second}) {
    EXPECT_GE(r->params_version, 2);
    EXPECT_NEAR(r->final_mem.c1, identified().mem.c1, 0.1 * identified().mem.c1);
  }
  EXPECT_LT(reid.second.stats.rms_true_m, 27.9e-9 / 5);
  EXPECT_LT(reid.second.stats.rms_true_m, table["MEM, wrong parameters"].second.stats.rms_true_m);
}

}  // namespace
}  // namespace hystloop
