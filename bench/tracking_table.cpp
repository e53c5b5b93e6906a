// tracking_table: the tracking figures of docs/BENCHMARKS.md, as tests/sim/tracking_test.cpp
// computes them, printed as a Markdown table beside the MEM paper's measured figures.
//
// In process and faster than real time (common/sim/loop_simulation.hpp): the Banning stage
// (Tables 1-2, 1 nm RMS sensor noise, seed 7), every model identified from the MEM paper's
// identification experiment (250 V sin(20 pi t), 2 s) run through the loop, then the reference
// y_d = -1.6 um cos(2 pi t) tracked with each feedforward, without and with PI feedback
// (kp 0.1, ki 600 1/s); RMS error over t in [4, 8) s against the true position.
//
// Then the re-identification table, without and with re-identification side by side,
// from MEM's deliberately wrong start: RMS over [8, 12) s of a 12 s run, and with the stage's
// gain drifting +10 % over 30 s, over [20, 30) s of a 30 s run.
//
// Then the line-rate scans (sim/scan_experiment.hpp): triangles and sines at 10-200 Hz with the
// models identified from a 10 Hz sine of the line's loops and the best of them (--model auto), without and
// with the stage's inverse (with it, the hysteresis fitted on the samples with the stage taken
// out), then with learning; RMS and max against the true position over the
// periods [20, 30) after the shape is entered, the bridge's clamped ticks and the periods until
// every period is at most 1 nm RMS.
//
//   tracking_table            prints the tables (Markdown) and the identified MEM parameters
//   tracking_table --scan     prints the scan table only
//   tracking_table --scan --block-ticks N   the same with sensor blocks of N ticks (default 10)
//   tracking_table --scan --two-mode        the scan table on a two-mode stage with delay (sim/tracking_experiment.hpp)
//   tracking_table --scan --class           learning off / on over other stages and hysteresis models
//   tracking_table --help     this text

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "bridge/bridge_settings.hpp"
#include "core/config.hpp"
#include "loop/servo_notches.hpp"
#include "sim/scan_experiment.hpp"
#include "sim/tracking_experiment.hpp"

namespace {

// One row of the re-identification table: without / with, feedforward only and with the servo.
void reid_row(const char* name, const hystloop::TrackingExperiment& e, const hystloop::IdentifiedModels& id,
              hystloop::TrackingOptions o) {
  using namespace hystloop;
  const Reidentify reid = o.reidentify;
  double rms[2][2] = {};
  TrackingRun last;
  for (int fb = 0; fb < 2; ++fb) {
    o.feedback = fb == 1;
    for (int on = 0; on < 2; ++on) {
      o.reidentify = on == 1 ? reid : Reidentify::off;
      last = run_tracking(e, id, o);
      rms[fb][on] = last.stats.rms_true_m * 1e9;
      if (fb == 0 && on == 1) {
        std::printf("| %s | %.2f nm | %.2f nm | %s, %zu swaps (%d worse) |", name, rms[0][0], rms[0][1],
                    std::string(to_string(last.final_kind)).c_str(), last.swaps.size(), last.worse_swaps);
      }
    }
  }
  std::printf(" %.2f nm | %.2f nm |\n", rms[1][0], rms[1][1]);
  std::fflush(stdout);
}

std::string cell(const hystloop::ScanRun& r) {
  if (r.refused) return "refused";
  char buf[96];
  std::snprintf(buf, sizeof buf, "%.2f / %.1f nm%s", r.stats.rms_true_m * 1e9, r.stats.max_abs_true_m * 1e9,
                r.clamped_ticks > 0 ? (", " + std::to_string(r.clamped_ticks) + " clamped").c_str() : "");
  return buf;
}

// The line-rate table of docs/TRACKING.md ("Scans at line rate").
bool scan_table(int block_ticks, const hystloop::TrackingExperiment& experiment, bool servo,
                const hystloop::ScanOptions& servo_options = {}) {
  using namespace hystloop;
  std::printf(
      "| reference | corner | model | servo, no stage inverse | + stage inverse | + learning, periods "
      "[20, 30) | periods to <= 1 nm |\n| --- | --- | --- | --- | --- | --- | --- |\n");
  bool all_taken = true;
  for (const ScanReference& r : scan_references()) {
    ScanOptions o = servo_options;
    o.block_ticks = block_ticks;
    o.servo = servo;
    // Without the stage's inverse the hysteresis model is fitted u -> y, the stage's lag in it; with
    // it, on the samples with that stage taken out, so that the lag is not corrected twice.
    o.stage_inverse = false;
    const IdentifiedModels id = identify_for_scan(experiment, r.amplitude_m);
    const ScanRun plain = run_scan(experiment, id, r, o);
    o.stage_inverse = true;
    const IdentifiedModels id_removed = identify_for_scan(experiment, r.amplitude_m, scan_stage(experiment, o));
    if (id.ranking.empty() || id_removed.ranking.empty()) return false;
    const ScanRun inverse = run_scan(experiment, id_removed, r, o);
    o.learning = true;
    const ScanRun learned = run_scan(experiment, id_removed, r, o);
    all_taken = all_taken && !inverse.refused && !learned.refused;
    char corner[32] = "—";
    if (r.shape == TrajectoryShape::kTriangle) std::snprintf(corner, sizeof corner, "%.2f ms", inverse.corner_s * 1e3);
    std::string name = r.name;
    if (inverse.shaped) {  // scaled into the limits, the servo's reserve included
      char to[64];
      std::snprintf(to, sizeof to, " (shaped to %.3g um)", inverse.amplitude_m * 1e6);
      name += to;
    }
    std::printf("| %s | %s | %s | %s | %s | %s | %d |\n", name.c_str(), corner, to_string(inverse.mode),
                cell(plain).c_str(), cell(inverse).c_str(), cell(learned).c_str(), learned.periods_to_converge);
    if (inverse.refused) std::printf("\n(refused: %s)\n", inverse.reason.c_str());
    std::fflush(stdout);
  }
  return all_taken;
}

// The servo of deploy/config/two-mode/bridge.yaml (the product's is tuned for Banning's stage, and
// unstable on this one): its gains and notches into the scan's options.
hystloop::ScanOptions two_mode_servo() {
  using namespace hystloop;
  const BridgeSettings settings =
      load_bridge_settings(Config::load_file(std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/two-mode/bridge.yaml"));
  const FeedbackGains& g = settings.servo_of(0);
  ScanOptions o;
  // How far up the stage model is known (its identification's), as the two-mode compensator has it.
  o.stage_known_to_hz = Config::load_file(std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/two-mode/compensator.yaml")
                            .get<double>("stage.known_to_hz", 0.0);
  o.kp = g.kp;
  o.ki = g.ki;
  o.notch_hz = g.notch_hz;
  o.notch_q = g.notch_q;
  o.notch2_hz = g.notch2_hz;
  o.notch2_q = g.notch2_q;
  return o;
}

// A line learned and not: the two runs, and the worst period with learning against the same
// period without.
struct LearningPair {
  hystloop::ScanRun off, on;
  double worst = 0.0;
};
LearningPair learning_off_and_on(const hystloop::TrackingExperiment& e, const hystloop::IdentifiedModels& id,
                                 const hystloop::ScanReference& r, hystloop::ScanOptions o) {
  LearningPair p;
  o.learning = false;
  p.off = run_scan(e, id, r, o);
  o.learning = true;
  p.on = run_scan(e, id, r, o);
  for (std::size_t k = 0; k < p.on.rms_per_period_m.size() && k < p.off.rms_per_period_m.size(); ++k)
    p.worst = std::max(p.worst, p.on.rms_per_period_m[k] / p.off.rms_per_period_m[k]);
  return p;
}

// Learning beside a deliberately wrong model of the two-mode stage: every period's RMS with
// learning against the same period's without, the worst ratio, and what learning clamped.
bool wrong_model_table(bool servo, bool known_band) {
  using namespace hystloop;
  const TrackingExperiment e = two_mode_experiment();
  const double delay_s = e.series_stage.delay_s;
  struct Wrong {
    const char* name;
    LinearStageSpec stage;
    double gain = 1.0;  // of the hysteresis model
  };
  const std::vector<Wrong> wrongs = {
      {"dominant mode 10 % high", LinearStageSpec::sum_of_modes({{858.0, 0.03, 0.92}, {2400.0, 0.02, 0.08}}, delay_s)},
      {"dominant mode 10 % low", LinearStageSpec::sum_of_modes({{702.0, 0.03, 0.92}, {2400.0, 0.02, 0.08}}, delay_s)},
      {"one tick of delay left out",
       LinearStageSpec::sum_of_modes({{780.0, 0.03, 0.92}, {2400.0, 0.02, 0.08}}, delay_s - 1e-4)},
      {"second mode left out", LinearStageSpec::sum_of_modes({{780.0, 0.03, 1.0}}, delay_s)},
      {"hysteresis gain x 1.5", e.series_stage, 1.5},
  };
  std::printf(
      "| model error | reference | learning off | learning on, periods [20, 30) | worst period on / off | clamped "
      "(off, on) |\n| --- | --- | --- | --- | --- | --- |\n");
  bool held = true;
  for (const ScanReference& r : scan_references()) {
    if (r.shape == TrajectoryShape::kSine && r.frequency_hz != 100.0) continue;  // the 10, 50 Hz triangles, 100 Hz sine
    if (r.shape == TrajectoryShape::kTriangle && r.frequency_hz > 50.0) continue;
    for (const Wrong& w : wrongs) {
      // The learner alone beside the wrong model, or (--servo) with deploy/config/two-mode's servo; a
      // wrong model claims no band it is known in (the learning stays below its lowest mode) unless
      // --known-band: then it keeps the band measured for the true stage, a claim now false.
      ScanOptions o = two_mode_servo();
      o.servo = servo;
      if (!known_band) o.stage_known_to_hz = 0.0;
      o.stage_inverse = true;
      o.stage_model = w.stage;
      o.mode = FeedforwardMode::kPi;
      IdentifiedModels id = identify_for_scan(e, r.amplitude_m, scan_stage(e, o));
      for (double& weight : id.pi.weights) weight *= w.gain;
      const auto [off, on, worst] = learning_off_and_on(e, id, r, o);
      held = held && !on.refused && worst <= 1.1 && on.clamped_ticks <= off.clamped_ticks;
      std::printf("| %s | %s | %s | %s | %.2f | %llu, %llu |\n", w.name, r.name.c_str(), cell(off).c_str(),
                  cell(on).c_str(), worst, static_cast<unsigned long long>(off.clamped_ticks),
                  static_cast<unsigned long long>(on.clamped_ticks));
      std::fflush(stdout);
    }
  }
  return held;
}

// Plants of the class the product is for, none of them the one the defaults were tuned on: each a
// hysteresis model, then a linear stage with delay, 1 nm of sensor noise. The compensator inverts
// the plant's own stage (a perfect identification; the measured band left out, so learning stays
// below the lowest mode) and the bridge runs the servo hystloop-identify suggests for that stage
// (loop/servo_notches.hpp: notches, kp 0, the largest ki keeping 10 dB / 50 deg). Per plant and
// line: learning off and on, the worst period with learning against the same period without, and
// the ticks clamped. Exit 1 when a line is refused, a period with learning exceeds 1.1 times its
// learning-off RMS, or learning adds a clamp (the MEM plant's rows do: see docs/TRACKING.md).
bool class_table() {
  using namespace hystloop;
  struct Plant {
    const char* name;
    LinearStageSpec stage;
    HysteresisPlantSpec hysteresis{};
  };
  HysteresisPlantSpec bouc_wen = HysteresisPlantSpec::named("bouc_wen");
  bouc_wen.bouc_wen.d = 7.4e-9;  // the stroke of a 250 V stack (models/bouc_wen.hpp)
  bouc_wen.bouc_wen.beta = 0.006;
  bouc_wen.bouc_wen.gamma = 0.002;
  const HysteresisPlantSpec mem = HysteresisPlantSpec::named("mem");
  const LinearStageSpec two_mode = two_mode_experiment().series_stage;
  const std::vector<Plant> plants = {
      {"two modes 780 Hz + 2.4 kHz, 1.5 ticks (the example)", two_mode},
      {"one mode 450 Hz zeta 0.02, 2.5 ticks", LinearStageSpec::sum_of_modes({{450.0, 0.02, 1.0}}, 2.5e-4)},
      {"1.1 kHz zeta 0.05, zero at +3 kHz (non-minimum phase), 1 tick",
       LinearStageSpec::zero_pole({{3000.0, 0.0}}, {{-55.0, 1100.0}}, 1e-4)},
      {"three modes 600 Hz / 1.5 kHz / 3.2 kHz, 1.5 ticks",
       LinearStageSpec::sum_of_modes({{600.0, 0.03, 0.7}, {1500.0, 0.02, 0.2}, {3200.0, 0.02, 0.1}}, 1.5e-4)},
      {"the two modes behind Bouc-Wen hysteresis", two_mode, bouc_wen},
      {"the two modes behind MEM (Ramberg-Osgood) hysteresis", two_mode, mem},
  };
  std::printf(
      "| plant | servo (suggested) | reference | learning off | learning on, periods [20, 30) | worst period on / off "
      "| "
      "clamped (off, on) |\n| --- | --- | --- | --- | --- | --- | --- |\n");
  bool held = true;
  for (const Plant& p : plants) {
    TrackingExperiment e = two_mode_experiment();
    e.series_stage = p.stage;
    e.series_hysteresis = p.hysteresis;
    const StageServo servo = servo_for_stage(p.stage, FeedbackGains{});
    char servo_cell[128];
    if (servo.gains.ki > 0.0) {
      std::snprintf(servo_cell, sizeof servo_cell, "ki %.0f/s, %zu notch%s (%.1f dB / %.0f deg)", servo.gains.ki,
                    servo.notches.size(), servo.notches.size() == 1 ? "" : "es", servo.worst.gain_margin_dB,
                    servo.worst.phase_margin_deg);
    } else {
      std::snprintf(servo_cell, sizeof servo_cell, "off (no ki keeps %g dB / %g deg)", kServoDesignGainMargin_dB,
                    kServoDesignPhaseMargin_deg);
    }
    for (const ScanReference& r : scan_references()) {
      if (r.shape == TrajectoryShape::kSine && r.frequency_hz != 100.0)
        continue;  // the 10, 50 Hz triangles, 100 Hz sine
      if (r.shape == TrajectoryShape::kTriangle && r.frequency_hz > 50.0) continue;
      ScanOptions o;
      o.servo = servo.gains.ki > 0.0;
      o.kp = 0.0;
      o.ki = servo.gains.ki;
      o.notch_hz = servo.gains.notch_hz;
      o.notch_q = servo.gains.notch_q;
      o.notch2_hz = servo.gains.notch2_hz;
      o.notch2_q = servo.gains.notch2_q;
      o.stage_inverse = true;
      const IdentifiedModels id = identify_for_scan(e, r.amplitude_m, scan_stage(e, o));
      if (id.ranking.empty()) {
        std::printf("| %s | %s | %s | no model identified | | | |\n", p.name, servo_cell, r.name.c_str());
        held = false;
        continue;
      }
      const auto [off, on, worst] = learning_off_and_on(e, id, r, o);
      held = held && !off.refused && !on.refused && worst <= 1.1 && on.clamped_ticks <= off.clamped_ticks;
      std::printf("| %s | %s | %s | %s | %s | %.2f | %llu, %llu |\n", p.name, servo_cell, r.name.c_str(),
                  cell(off).c_str(), cell(on).c_str(), worst, static_cast<unsigned long long>(off.clamped_ticks),
                  static_cast<unsigned long long>(on.clamped_ticks));
      if (off.refused || on.refused) std::printf("\n(refused: %s)\n\n", (off.refused ? off : on).reason.c_str());
      std::fflush(stdout);
    }
  }
  return held;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace hystloop;
  if (argc > 1) {
    const bool help = std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0;
    if (std::strcmp(argv[1], "--scan") == 0 && argc >= 4 && std::strcmp(argv[2], "--two-mode") == 0 &&
        std::strcmp(argv[3], "--wrong-models") == 0) {
      bool servo = false, known_band = false;
      for (int i = 4; i < argc; ++i) {
        if (std::strcmp(argv[i], "--servo") == 0) {
          servo = true;
        } else if (std::strcmp(argv[i], "--known-band") == 0) {
          known_band = true;
        } else {
          std::fprintf(stderr, "tracking_table: --wrong-models takes --servo and --known-band (got %s)\n", argv[i]);
          return 2;
        }
      }
      return wrong_model_table(servo, known_band) ? 0 : 1;
    }
    if (std::strcmp(argv[1], "--scan") == 0 && argc == 3 && std::strcmp(argv[2], "--class") == 0) {
      return class_table() ? 0 : 1;
    }
    if (std::strcmp(argv[1], "--scan") == 0 && argc == 3 && std::strcmp(argv[2], "--two-mode") == 0) {
      return scan_table(ScanOptions{}.block_ticks, two_mode_experiment(), true, two_mode_servo()) ? 0 : 1;
    }
    if (std::strcmp(argv[1], "--scan") == 0) {
      int block_ticks = ScanOptions{}.block_ticks;
      if (argc == 4 && std::strcmp(argv[2], "--block-ticks") == 0) {
        block_ticks = std::atoi(argv[3]);
        if (block_ticks < 1 || block_ticks > 1000) {
          std::fprintf(stderr, "tracking_table: --block-ticks must be in [1, 1000] (got %s)\n", argv[3]);
          return 2;
        }
      } else if (argc != 2) {
        std::fprintf(stderr, "tracking_table: --scan takes only --block-ticks N\n");
        return 2;
      }
      return scan_table(block_ticks, TrackingExperiment{}, true) ? 0 : 1;
    }
    std::printf(
        "usage: tracking_table [--scan [--block-ticks N | --class | --two-mode [--wrong-models [--servo] "
        "[--known-band]]]] "
        "[--help]\nPrints the "
        "tracking "
        "tables of "
        "docs/BENCHMARKS.md and docs/TRACKING.md (--scan: the line-rate scan table only; --block-ticks: "
        "sensor blocks of N ticks, default 10; --two-mode: the scan table on a two-mode stage with 1.5 ticks "
        "of delay, its linear stage inverted with preview, the servo of deploy/config/two-mode; --class: other "
        "stages (modes, delays, a non-minimum-phase zero) and hysteresis models with the servo suggested for each, "
        "learning off and on, exit 1 when a period with learning exceeds 1.1 times it or learning adds a clamp; "
        "--wrong-models: "
        "learning beside a "
        "deliberately wrong model of that stage, every period against learning off, the servo off unless --servo; exit "
        "1 when a period exceeds "
        "1.1 times it or learning adds a clamp).\n");
    return help ? 0 : 2;
  }
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
  std::printf(
      "| feedforward | simulation: feedforward only (true / measured) | simulation: + PI feedback (true / measured) "
      "| MEM paper, real actuator, feedforward only |\n| --- | --- | --- | --- |\n");
  for (const Row& r : rows) {
    const MemParams& start = r.wrong_start ? wrong : id.mem;
    const TrackingStats ff = run_tracking(experiment, id, r.mode, false, r.reid, start).stats;
    const TrackingStats fb = run_tracking(experiment, id, r.mode, true, r.reid, start).stats;
    std::printf("| %s | %.2f / %.2f nm | %.2f / %.2f nm | %s |\n", r.name, ff.rms_true_m * 1e9, ff.rms_measured_m * 1e9,
                fb.rms_true_m * 1e9, fb.rms_measured_m * 1e9, r.paper);
    std::fflush(stdout);
  }
  std::printf(
      "\n| from MEM's wrong start | ff only | ff + re-identification | model at the end | servo | servo + "
      "re-identification |\n| --- | --- | --- | --- | --- | --- |\n");
  TrackingExperiment twelve = experiment;
  twelve.track_s = 12.0;
  twelve.settle_s = 8.0;
  TrackingOptions o;
  o.start_mem = wrong;
  o.reidentify = Reidentify::mem;
  reid_row("MEM estimator, [8, 12) s", twelve, id, o);
  o.reidentify = Reidentify::select;
  o.selector.pinned = true;
  reid_row("selector, MEM pinned, [8, 12) s", twelve, id, o);
  o.selector.pinned = false;
  reid_row("selector, automatic, [8, 12) s", twelve, id, o);
  TrackingExperiment drift = experiment;
  drift.drift_fraction = 0.1;
  drift.drift_duration_s = 30.0;
  drift.track_s = 30.0;
  drift.settle_s = 20.0;
  o.start_mem = id.mem;  // the offline fit, then the gain drifts
  o.reidentify = Reidentify::mem;
  reid_row("gain +10 %/30 s, offline MEM start, MEM estimator, [20, 30) s", drift, id, o);
  o.reidentify = Reidentify::select;
  reid_row("gain +10 %/30 s, offline MEM start, automatic, [20, 30) s", drift, id, o);
  std::printf("\n");
  const bool scans = scan_table(hystloop::ScanOptions{}.block_ticks, experiment, true);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("\n(%.0f s of simulated loop at 10 kHz in %.1f s of wall time)\n",
              experiment.identify_s + 12 * experiment.track_s + 3 * 4 * 12.0 + 2 * 4 * 30.0, seconds);
  return id.ok && scans ? 0 : 1;
}
