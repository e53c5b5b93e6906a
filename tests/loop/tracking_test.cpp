// The whole control law on the Banning stage (Tables 1-2, 1 nm sensor noise), in process and
// faster than real time: identify every model from the MEM paper's identification experiment
// (250 V sin(20 pi t)) run through the loop, then track the MEM paper's reference (24)
// y_d = -1.6 um cos(2 pi t) with each feedforward, with and without feedback, and with online
// re-identification from deliberately wrong MEM parameters. Prints the table; asserts the
// figures the product promises.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "ident/katalenic_fit.hpp"
#include "ident/linear_fit.hpp"
#include "ident/mem_fit.hpp"
#include "ident/online_mem_estimator.hpp"
#include "ident/pi_fit.hpp"
#include "loop/loop_simulation.hpp"

namespace hystloop {
namespace {

constexpr double kIdentSeconds = 2.0;
constexpr double kTrackSeconds = 8.0;
constexpr double kSettleSeconds = 4.0;  // error measured over [settle, track): the last 4 periods

LoopSimulationConfig base_config() {
  LoopSimulationConfig c;
  c.stage.noise_rms_m = 1e-9;
  c.stage.seed = 7;
  c.compensator.mode = FeedforwardMode::kOff;
  return c;
}

struct Identified {
  MemParams mem;
  PiParams pi;
  KatalenicParams katalenic;
  LinearParams linear;
};

// Runs the identification experiment through the loop and fits every model to it.
const Identified& identified() {
  static const Identified result = [] {
    LoopSimulation sim(base_config());
    ExperimentSpec e;  // 250 V, 10 Hz: the MEM paper's identification input
    e.duration_s = kIdentSeconds;
    sim.compensator().start_experiment(e);
    sim.run(kIdentSeconds + 0.01);
    std::vector<double> u, y;
    for (const LoopTick& t : sim.history()) {
      if (t.t_s < 0.01 || t.t_s > kIdentSeconds) continue;  // the lead ticks held 0 V
      u.push_back(t.u_V);
      y.push_back(t.y_m);
    }
    Identified id;
    const MemFitResult mem = fit_mem(u, y);
    EXPECT_EQ(mem.status, FitStatus::ok) << mem.reason;
    id.mem = mem.params;
    const PiFitResult pi = fit_pi(u, y);
    EXPECT_TRUE(pi.ok()) << pi.reason;
    id.pi = to_pi_params(pi);
    const KatalenicFitResult kat = fit_katalenic(u, y);
    EXPECT_TRUE(kat.ok()) << kat.reason;
    id.katalenic = kat.params;
    const LinearFitResult lin = fit_linear(u, y);
    EXPECT_TRUE(lin.ok()) << lin.reason;
    id.linear = to_linear_params(lin);
    std::printf("identified MEM c1=%.4g m/V c2=%.4g c3=%.4g (residual %.2f nm)\n", id.mem.c1, id.mem.c2, id.mem.c3,
                mem.residual_rms_m * 1e9);
    return id;
  }();
  return result;
}

struct TrackRun {
  TrackingStats stats;
  int params_version = 0;
  MemParams final_mem{};
};

TrackRun track(FeedforwardMode mode, bool feedback, bool reidentify, const MemParams* start_mem = nullptr) {
  const Identified& id = identified();
  LoopSimulationConfig c = base_config();
  c.compensator.mode = mode;
  c.compensator.mem = start_mem ? *start_mem : id.mem;
  c.compensator.pi = id.pi;
  c.compensator.katalenic = id.katalenic;
  c.compensator.linear = id.linear;
  if (feedback) {
    c.compensator.feedback.ki = 600.0;
    c.compensator.feedback.kp = 0.1;
    c.compensator.feedback.nominal_gain_m_per_V = id.linear.gain;
  }
  LoopSimulation sim(c);
  sim.compensator().set_trajectory(mem_paper_reference(0.5, 0.5, 0.0));  // approach over 0.5 s

  OnlineMemOptions opt;
  opt.window_samples = 40000;          // 4 s: four branches of the 1 Hz reference
  opt.fit.reversal_dead_band_V = 1.0;  // feedback jitter on u is not a branch
  OnlineMemEstimator estimator(opt, c.compensator.mem);
  std::int32_t version = 1;
  const auto refit_every = static_cast<std::int64_t>(1.0 / c.compensator.dt_s);
  sim.run(kTrackSeconds, [&](const LoopTick& t) {
    if (!reidentify) return;
    estimator.feed(t.u_V, t.y_m);
    if (t.k > 0 && t.k % refit_every == 0) {
      const MemRefitOutcome out = estimator.refit();
      if (std::getenv("HYSTLOOP_DEBUG")) std::printf("refit t=%.1f %s accepted=%d %s c1=%.3g c2=%.3g c3=%.3g holdout %.2f/%.2f nm\n", t.t_s, to_string(out.status).data(), out.accepted, out.reason.c_str(), out.candidate.c1, out.candidate.c2, out.candidate.c3, out.holdout_rms_candidate_m*1e9, out.holdout_rms_in_use_m*1e9);
      if (out.accepted) sim.compensator().offer_mem_params(estimator.params(), ++version);
    }
  });
  return {sim.tracking(kSettleSeconds, kTrackSeconds), sim.compensator().params_version(),
          sim.compensator().mem_params()};
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
