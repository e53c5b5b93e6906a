// servo_margins: the bridge servo's stability margins on Banning's stage and what they buy, for
// docs/TRACKING.md. Reproducible: no clock, fixed seeds.
//
// 1. The discrete loop's frequency response (common/loop/servo_loop_response.hpp: the ZOH
//    second-order stage, k = 1.17e8 1/s^2, c = 2.03e3 1/s; the PI; the notch): gain and phase
//    margin, |S| at 50 Hz, the peak of |S| and the largest stable ki, for the former defaults,
//    the defaults of deploy/config/bridge.yaml and the same gains without the notch. "sim" is the
//    loop the simulator runs (the position sampled at the tick's end reaches the next tick);
//    "card" adds the tick of a DAQ card that reads the sensor right after writing the voltage.
// 2. The defaults' margins when the resonance or the stage's local slope is not what was assumed.
// 3. The in-process loop (common/sim/loop_simulation.hpp: Banning's stage with its hysteresis,
//    1 nm sensor noise): the largest ki (kp 0.1) that still tracks the 1 Hz MEM-paper cosine,
//    with and without the notch; then that cosine with every feedforward, the former defaults
//    (run_tracking, as tests/sim/tracking_test) against the defaults; then a 1 um 100 Hz sine
//    whose feedforward the slew limit clamps, feedforward only against the servo.
// 4. kp against the sensor's noise at the slew limit: the servo's tick-to-tick step for 1 nm of
//    white error, and the 200 Hz, 0.25 um scan line (sim/scan_experiment.hpp; its feedforward
//    needs ~98 % of the slew) over 12 noise seeds, 4 s each: ticks whose servo step the bridge
//    clipped, and the RMS, for kp 0.1 and the defaults' kp.
//
//   servo_margins [CONFIG]    CONFIG: the bridge's settings (default deploy/config/bridge.yaml)

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "bridge/bridge_settings.hpp"
#include "core/config.hpp"
#include "loop/servo_loop_response.hpp"
#include "sim/scan_experiment.hpp"
#include "sim/tracking_experiment.hpp"

namespace {

using namespace hystloop;

FeedbackGains pi(double kp, double ki, double notch_hz = 0.0, double notch_q = 2.0) {
  FeedbackGains g;
  g.kp = kp;
  g.ki = ki;
  g.notch_hz = notch_hz;
  g.notch_q = notch_q;
  return g;
}

std::string notch_text(const FeedbackGains& g) {
  char buf[96];
  if (!g.has_notch() && !g.has_notch2()) return "none";
  if (!g.has_notch2()) {
    std::snprintf(buf, sizeof buf, "%.0f Hz, Q %.2g", g.notch_hz, g.notch_q);
  } else if (!g.has_notch()) {
    std::snprintf(buf, sizeof buf, "%.0f Hz, Q %.2g", g.notch2_hz, g.notch2_q);
  } else {
    std::snprintf(buf, sizeof buf, "%.0f Hz, Q %.2g; %.0f Hz, Q %.2g", g.notch_hz, g.notch_q, g.notch2_hz, g.notch2_q);
  }
  return buf;
}

void margins_row(const char* name, const FeedbackGains& g, const ServoLoopModel& stage = {}) {
  std::printf("| %s | %.2g | %.0f | %s |", name, g.kp, g.ki, notch_text(g).c_str());
  for (int delay = 0; delay <= 1; ++delay) {
    ServoLoopModel model = stage;
    model.extra_delay_ticks = delay;
    const ServoLoopResponse r(g, model);
    const LoopMargins m = r.margins();
    if (!m.stable) {
      std::printf(" unstable | | |");
    } else {
      std::printf(" %.1f dB (%.0f Hz) | %.0f° (%.0f Hz) | %.3f / %.2f |", m.gain_margin_dB, m.gain_margin_hz,
                  m.phase_margin_deg, m.crossover_hz, r.sensitivity(50.0), m.sensitivity_peak);
    }
    std::printf(" %.0f |", largest_stable_ki(g, model));
  }
  std::printf("\n");
}

struct Tracked {
  double rms_m = 0.0;  // of the true error over [settle_s, track_s)
  std::uint64_t clamped_ticks = 0;
};

// run_tracking without re-identification, with the whole FeedbackGains (TrackingExperiment has
// kp and ki only).
Tracked track(const TrackingExperiment& e, const IdentifiedModels& id, FeedforwardMode mode, const MemParams& start_mem,
              const FeedbackGains* servo) {
  LoopSimulationConfig c = tracking_loop_config(e);
  c.compensator.mode = mode;
  c.compensator.models.mem = start_mem;
  c.compensator.models.pi = id.pi;
  c.compensator.models.katalenic = id.katalenic;
  c.compensator.models.linear = id.linear;
  c.compensator.u_min_V = c.limits.u_min_V;
  c.compensator.u_max_V = c.limits.u_max_V;
  c.compensator.slew_V_per_s = c.limits.slew_V_per_s;
  if (servo != nullptr) {
    c.servo = *servo;
    c.servo.nominal_gain_m_per_V = id.linear.gain;
  }
  LoopSimulation sim(c);
  const TrajectorySpec reference = mem_paper_reference(0.5, 0.5, 0.0);
  sim.compensator().set_trajectory(reference, reference.start_s);
  sim.run(e.track_s);
  Tracked out{sim.tracking(e.settle_s, e.track_s).rms_true_m, sim.bridge().counters().clamped_either};
  return out;
}

// A 1 um 100 Hz sine through the bridge alone, its feedforward the linear inverse y_ref / gain:
// 1e5 V/s at the zero crossings, twice the slew limit. RMS of the true error over [0.1, 0.3) s.
double slew_clamped_sine(const FeedbackGains* servo, double gain_m_per_V, std::uint64_t* clamped) {
  const ActuatorLimits limits;
  FeedbackGains g = servo != nullptr ? *servo : FeedbackGains{};
  g.nominal_gain_m_per_V = gain_m_per_V;
  BridgeCore bridge(limits, g, 1e-4);
  SimulatedStageConfig sc;
  SimulatedStage stage(sc);
  bridge.arm(0);
  double y = 0.0, sum = 0.0;
  int n = 0;
  for (std::int64_t k = 0; k < 3000; ++k) {
    const double t = static_cast<double>(k) * 1e-4;
    const double ref = 1e-6 * std::sin(2.0 * std::numbers::pi * 100.0 * t);
    bridge.submit({k, ref / gain_m_per_V, ref, 1, 0});
    const BridgeTick b = bridge.tick(k, y);
    y = stage.step(b.u_applied_V, t, 1e-4);
    if (t >= 0.1) {
      const double e = ref - stage.true_position_m();
      sum += e * e;
      ++n;
    }
  }
  *clamped = bridge.counters().clamped_either;
  return std::sqrt(sum / n);
}

// RMS of the servo's step from one tick to the next [V] for white error of 1 nm RMS, open loop.
double servo_noise_step_V(const FeedbackGains& g) {
  FeedbackController c(g);
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0.0, 1e-9);
  constexpr int kSettle = 1000, kTicks = 200000;
  double last = 0.0, sum = 0.0;
  for (int k = 0; k < kSettle + kTicks; ++k) {
    const double u = c.update(noise(rng), 0.0, 1.0 / g.tick_rate_hz);
    if (k >= kSettle) sum += (u - last) * (u - last);
    last = u;
  }
  return std::sqrt(sum / kTicks);
}

void kp_at_the_slew_limit(const FeedbackGains& defaults) {
  std::printf(
      "\nkp against the sensor's noise at the slew limit: the servo's step for 1 nm of white error (open loop), "
      "and the 200 Hz, 0.25 um sine over 12 seeds x 4 s (clamped ticks, runs with any, mean RMS of the true "
      "error), its feedforward at 98 %% of the slew (no reserve for the servo) and scaled into the default "
      "reserve\n\n| kp | servo step | servo reserve | amplitude | clamped ticks | runs with a clamp | RMS "
      "|\n|---|---|---|---|---|---|---|\n");
  const ScanReference line{"sine 200 Hz 0.25 um", TrajectoryShape::kSine, 0.25e-6, 200.0};
  constexpr int kSeeds = 12;
  for (const double reserve : {0.0, ScanOptions{}.servo_slew_reserve}) {
    for (const double kp : {0.1, defaults.kp}) {
      FeedbackGains g = defaults;
      g.kp = kp;
      std::uint64_t clamped = 0;
      int runs_clamped = 0;
      double rms_sum = 0.0, amplitude_sum = 0.0;
      for (int s = 0; s < kSeeds; ++s) {
        TrackingExperiment e;
        e.seed = 7 + 13 * static_cast<std::uint64_t>(s);
        ScanOptions o;
        o.kp = g.kp;
        o.ki = g.ki;
        o.notch_hz = g.notch_hz;
        o.notch_q = g.notch_q;
        o.servo_slew_reserve = reserve;
        o.measure_periods = static_cast<int>(4.0 * line.frequency_hz);
        const ScanRun run = run_scan(e, identify_for_scan(e, line.amplitude_m), line, o);
        clamped += run.clamped_ticks;
        runs_clamped += run.clamped_ticks > 0 ? 1 : 0;
        rms_sum += run.stats.rms_true_m;
        amplitude_sum += run.amplitude_m;
      }
      std::printf("| %.2g | %.3f V | %.0f %% | %.3f um | %llu | %d of %d | %.3f nm |\n", kp, servo_noise_step_V(g),
                  100.0 * reserve, amplitude_sum / kSeeds * 1e6, static_cast<unsigned long long>(clamped), runs_clamped,
                  kSeeds, rms_sum / kSeeds * 1e9);
      std::fflush(stdout);
    }
  }
}

}  // namespace

// The margins of the same servo on the two-mode stage (780 Hz zeta 0.03, 92 %; 2.4 kHz zeta 0.02,
// 8 %; 1.5 ticks of delay): the defaults, tuned for Banning's stage, a notch on its first mode, and
// deploy/config/two-mode's servo (a notch on each mode, as loop/servo_notches.hpp sets them).
int two_mode_margins() {
  ServoLoopModel stage;
  stage.linear = LinearStageSpec::sum_of_modes({{780.0, 0.03, 0.92}, {2400.0, 0.02, 0.08}}, 1.5e-4);
  std::printf(
      "Servo margins on the two-mode stage (780 Hz zeta 0.03, 92 %%; 2.4 kHz zeta 0.02, 8 %%; 1.5 ticks of "
      "delay)\n\n| gains | kp | ki [1/s] | notch | sim: gain margin | sim: phase margin | sim: abs(S) at 50 Hz / "
      "peak | sim: largest stable ki | card: gain margin | card: phase margin | card: abs(S) at 50 Hz / peak | "
      "card: largest stable ki |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  margins_row("defaults (bridge.yaml)", pi(0.05, 2000.0, 1720.0, 0.7), stage);
  margins_row("defaults without the notch", pi(0.05, 2000.0), stage);
  margins_row("notch on the 780 Hz mode", pi(0.05, 2000.0, 780.0, 0.5), stage);
  margins_row("integral only, notch on the mode", pi(0.0, 600.0, 780.0, 0.5), stage);
  const FeedbackGains two_mode =
      load_bridge_settings(Config::load_file(std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/two-mode/bridge.yaml"))
          .servo_of(0);
  margins_row("deploy/config/two-mode (notches from the model)", two_mode, stage);
  FeedbackGains one_notch = two_mode;
  one_notch.notch2_hz = 0.0;
  margins_row("the same without the second notch", one_notch, stage);
  return 0;
}

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/bridge.yaml";
  if (path == "--help" || path == "-h") {
    std::printf(
        "usage: servo_margins [BRIDGE_CONFIG | --two-mode]\nPrints the servo's margins and tracking tables "
        "(--two-mode: the margins on the two-mode stage with 1.5 ticks of delay only).\n");
    return 0;
  }
  if (path == "--two-mode") return two_mode_margins();
  const BridgeSettings settings = load_bridge_settings(Config::load_file(path));
  const FeedbackGains defaults = settings.servo;
  FeedbackGains defaults_no_notch = defaults;
  defaults_no_notch.notch_hz = 0.0;
  const FeedbackGains former = pi(0.1, 600.0);

  std::printf("Servo margins on Banning's stage (ZOH, 1.72 kHz, zeta 0.094), %s\n\n", path.c_str());
  std::printf(
      "| gains | kp | ki [1/s] | notch | sim: gain margin | sim: phase margin | sim: abs(S) at 50 Hz / peak | sim: "
      "largest stable ki | card: gain margin | card: phase margin | card: abs(S) at 50 Hz / peak | card: largest "
      "stable ki |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  margins_row("former defaults", former);
  margins_row("defaults (bridge.yaml)", defaults);
  margins_row("defaults without the notch", defaults_no_notch);
  FeedbackGains former_notched = former;
  former_notched.notch_hz = defaults.notch_hz;
  former_notched.notch_q = defaults.notch_q;
  margins_row("former defaults with the notch", former_notched);

  // The hysteresis moves the stage's local slope between about 2b - a and a of Table 1 (0.57 and
  // 1.36 x the nominal 6.3e-9 m/V); the resonance is known to the identification's accuracy.
  std::printf(
      "\nThe defaults when the stage is not as assumed (gain / phase margin, sim; card):\n\n"
      "| resonance | slope 0.57 x nominal | slope 1 x | slope 1.36 x |\n|---|---|---|---|\n");
  for (const double f_scale : {0.8, 0.9, 1.0, 1.1, 1.2}) {
    std::printf("| %.0f Hz |", ServoLoopModel{}.stage.natural_frequency() * f_scale / (2.0 * std::numbers::pi));
    for (const double slope : {0.57, 1.0, 1.36}) {
      for (int delay = 0; delay <= 1; ++delay) {
        ServoLoopModel model;
        model.stage.k *= f_scale * f_scale;
        model.stage.c *= f_scale;  // the same damping ratio
        model.slope_ratio = slope;
        model.extra_delay_ticks = delay;
        const LoopMargins m = ServoLoopResponse(defaults, model).margins();
        if (m.stable) {
          std::printf("%s%.1f dB / %.0f°", delay == 0 ? " " : "; ", m.gain_margin_dB, m.phase_margin_deg);
        } else {
          std::printf("%sunstable", delay == 0 ? " " : "; ");
        }
      }
      std::printf(" |");
    }
    std::printf("\n");
  }
  std::fflush(stdout);

  const TrackingExperiment e;
  const IdentifiedModels id = identify_models_through_loop(e);
  // Past the linear limit the loop rings at the resonance; the hysteresis (its slope falls after
  // every reversal of the ringing) holds it in a limit cycle instead of letting it grow.
  std::printf(
      "\nIn-process loop, PI-15 feedforward, 1 Hz MEM-paper cosine, kp 0.1: RMS of the true error over [4, 8) "
      "s (ticks clamped)\n\n| ki [1/s] | no notch | notch %s |\n|---|---|---|\n",
      notch_text(defaults).c_str());
  for (const double ki : {600.0, 1200.0, 1500.0, 1700.0, 2000.0, 3000.0, 6000.0, 9000.0, 10000.0, 12000.0}) {
    std::printf("| %.0f |", ki);
    for (const bool notch : {false, true}) {
      const FeedbackGains g = pi(0.1, ki, notch ? defaults.notch_hz : 0.0, defaults.notch_q);
      const Tracked t = track(e, id, FeedforwardMode::kPi, id.mem, &g);
      std::printf(" %.2f nm (%llu) |", t.rms_m * 1e9, static_cast<unsigned long long>(t.clamped_ticks));
    }
    std::printf("\n");
    std::fflush(stdout);
  }

  MemParams wrong = id.mem;
  wrong.c1 *= 0.6;
  wrong.c2 *= 1.8;
  struct Row {
    const char* name;
    FeedforwardMode mode;
    MemParams mem;
  };
  const Row rows[] = {{"linear", FeedforwardMode::kLinear, id.mem},
                      {"PI-15", FeedforwardMode::kPi, id.mem},
                      {"Katalenic", FeedforwardMode::kKatalenic, id.mem},
                      {"MEM", FeedforwardMode::kMem, id.mem},
                      {"MEM, wrong parameters", FeedforwardMode::kMem, wrong}};
  std::printf(
      "\n1 Hz MEM-paper cosine, RMS of the true error over [4, 8) s\n\n| feedforward | feedforward only | former "
      "defaults (run_tracking) | former defaults (here) | defaults (bridge.yaml) |\n|---|---|---|---|---|\n");
  for (const Row& r : rows) {
    const double ff = run_tracking(e, id, r.mode, false, false, r.mem).stats.rms_true_m;
    const double harness = run_tracking(e, id, r.mode, true, false, r.mem).stats.rms_true_m;
    const double here = track(e, id, r.mode, r.mem, &former).rms_m;
    const double now = track(e, id, r.mode, r.mem, &defaults).rms_m;
    std::printf("| %s | %.2f nm | %.2f nm | %.2f nm | %.2f nm |\n", r.name, ff * 1e9, harness * 1e9, here * 1e9,
                now * 1e9);
    std::fflush(stdout);
  }

  std::printf("\n1 um 100 Hz sine, linear feedforward clamped by the slew limit: RMS over [0.1, 0.3) s\n\n");
  std::printf("| servo | RMS | clamped ticks |\n|---|---|---|\n");
  std::uint64_t clamped = 0;
  const double gain = id.linear.gain;
  double rms = slew_clamped_sine(nullptr, gain, &clamped);
  std::printf("| none | %.1f nm | %llu |\n", rms * 1e9, static_cast<unsigned long long>(clamped));
  rms = slew_clamped_sine(&former, gain, &clamped);
  std::printf("| former defaults | %.1f nm | %llu |\n", rms * 1e9, static_cast<unsigned long long>(clamped));
  rms = slew_clamped_sine(&defaults, gain, &clamped);
  std::printf("| defaults | %.1f nm | %llu |\n", rms * 1e9, static_cast<unsigned long long>(clamped));
  kp_at_the_slew_limit(defaults);
  return id.ok ? 0 : 1;
}
