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
#include <cmath>
#include <cstdio>
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
constexpr double kSettleSeconds = 4.0;

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
  bool ok = true;
};

Identified identify() {
  LoopSimulation sim(base_config());
  ExperimentSpec e;
  e.duration_s = kIdentSeconds;
  sim.compensator().start_experiment(e);
  sim.run(kIdentSeconds + 0.01);
  std::vector<double> u, y;
  for (const LoopTick& t : sim.history()) {
    if (t.t_s < 0.01 || t.t_s > kIdentSeconds) continue;
    u.push_back(t.u_V);
    y.push_back(t.y_m);
  }
  Identified id;
  const MemFitResult mem = fit_mem(u, y);
  const PiFitResult pi = fit_pi(u, y);
  const KatalenicFitResult kat = fit_katalenic(u, y);
  const LinearFitResult lin = fit_linear(u, y);
  id.ok = mem.status == FitStatus::ok && pi.ok() && kat.ok() && lin.ok();
  id.mem = mem.params;
  id.pi = to_pi_params(pi);
  id.katalenic = kat.params;
  id.linear = to_linear_params(lin);
  std::printf("Identified MEM: c1 = %.4g m/V, c2 = %.4g, c3 = %.4g (fit residual %.2f nm)\n\n", id.mem.c1, id.mem.c2,
              id.mem.c3, mem.residual_rms_m * 1e9);
  return id;
}

TrackingStats track(const Identified& id, FeedforwardMode mode, bool feedback, bool reidentify, const MemParams& start) {
  LoopSimulationConfig c = base_config();
  c.compensator.mode = mode;
  c.compensator.mem = start;
  c.compensator.pi = id.pi;
  c.compensator.katalenic = id.katalenic;
  c.compensator.linear = id.linear;
  if (feedback) {
    c.compensator.feedback.ki = 600.0;
    c.compensator.feedback.kp = 0.1;
    c.compensator.feedback.nominal_gain_m_per_V = id.linear.gain;
  }
  LoopSimulation sim(c);
  sim.compensator().set_trajectory(mem_paper_reference(0.5, 0.5, 0.0));
  OnlineMemOptions opt;
  opt.window_samples = 40000;
  opt.fit.reversal_dead_band_V = 1.0;
  OnlineMemEstimator estimator(opt, c.compensator.mem);
  std::int32_t version = 1;
  const auto refit_every = static_cast<std::int64_t>(1.0 / c.compensator.dt_s);
  sim.run(kTrackSeconds, [&](const LoopTick& t) {
    if (!reidentify) return;
    estimator.feed(t.u_V, t.y_m);
    if (t.k > 0 && t.k % refit_every == 0) {
      const MemRefitOutcome out = estimator.refit();
      if (out.accepted) sim.compensator().offer_mem_params(estimator.params(), ++version);
    }
  });
  return sim.tracking(kSettleSeconds, kTrackSeconds);
}

}  // namespace
}  // namespace hystloop

int main() {
  using namespace hystloop;
  const auto t0 = std::chrono::steady_clock::now();
  const Identified id = identify();
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
    const TrackingStats ff = track(id, r.mode, false, r.reid, start);
    const TrackingStats fb = track(id, r.mode, true, r.reid, start);
    std::printf("| %s | %.2f / %.2f nm | %.2f / %.2f nm | %s |\n", r.name, ff.rms_true_m * 1e9, ff.rms_measured_m * 1e9,
                fb.rms_true_m * 1e9, fb.rms_measured_m * 1e9, r.paper);
    std::fflush(stdout);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("\n(%.0f s of simulated loop at 10 kHz in %.1f s of wall time)\n",
              kIdentSeconds + 12 * kTrackSeconds, seconds);
  return id.ok ? 0 : 1;
}
