// Scans at line rate on the simulated stage (sim/scan_experiment.hpp), in process: the references a
// lab runs, with the stage's inverse and the model identified for the line's loops, without and
// with learning, inside the actuator's limits. The figures are docs/TRACKING.md's
// (bench/tracking_table --scan prints them).
#include "sim/scan_experiment.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace hystloop {
namespace {

TEST(Scan, EveryLineRateTargetIsTrackedInsideTheLimits) {
  const TrackingExperiment experiment;  // Banning's stage, 1 nm sensor noise
  for (const ScanReference& r : scan_references()) {
    ScanOptions o;
    // Fitted without the stage the compensator inverts, as bench/tracking_table's columns with it.
    const IdentifiedModels models = identify_for_scan(experiment, r.amplitude_m, scan_stage(experiment, o));
    ASSERT_FALSE(models.ranking.empty()) << r.name;
    const ScanRun plain = run_scan(experiment, models, r, o);
    ASSERT_FALSE(plain.refused) << r.name << ": " << plain.reason;
    // The 200 Hz line's feedforward needs 98 % of the slew limit here, into the servo's reserve:
    // it is scaled to fit, by what the reserve takes; every other line is tracked as asked.
    if (r.frequency_hz >= 200.0) {
      EXPECT_TRUE(plain.shaped) << r.name;
      EXPECT_GE(plain.amplitude_m, 0.97 * r.amplitude_m) << r.name;
      EXPECT_NE(plain.reason.find("scaled"), std::string::npos) << plain.reason;
    } else {
      EXPECT_FALSE(plain.shaped) << r.name << ": " << plain.reason;
    }
    EXPECT_EQ(plain.clamped_ticks, 0u) << r.name;
    EXPECT_EQ(plain.counters.u_slew_clamped + plain.counters.u_clamped, 0u) << r.name;
    EXPECT_LE(plain.stats.rms_true_m, 2e-9) << r.name;  // with the stage's inverse, without learning
    o.learning = true;
    const ScanRun learned = run_scan(experiment, models, r, o);
    ASSERT_FALSE(learned.refused) << r.name;
    EXPECT_EQ(learned.clamped_ticks, 0u) << r.name;
    EXPECT_LE(learned.stats.rms_true_m, 1e-9) << r.name;  // periods [20, 30)
    EXPECT_LE(learned.stats.max_abs_true_m, 5e-9) << r.name;
    EXPECT_GE(learned.periods_to_converge, 0) << r.name;
    EXPECT_LE(learned.periods_to_converge, 20) << r.name;
    if (r.shape == TrajectoryShape::kTriangle) {
      EXPECT_GT(plain.corner_s, 0.0) << r.name;
    }
  }
}

TEST(Scan, LearningRepairsAModelFittedForOtherLoopsDespiteTheServo) {
  // The deployed PI-15 is fitted for a 1 um line's loops; a 0.5 um line at 100 Hz makes smaller
  // ones, on which it is off by several nm. Learning must remove that although the servo, acting
  // on y_ref - y, works against every correction (its sensitivity is 0.3 at 100 Hz): the learner
  // learns the feedforward's own error, and its excess over the limits is held back, so the
  // bridge never clamps.
  const TrackingExperiment experiment;
  const IdentifiedModels models = identify_for_scan(experiment, 1e-6);
  const ScanReference line = scan_references()[4];  // sine 100 Hz 0.5 um
  ASSERT_DOUBLE_EQ(line.amplitude_m, 0.5e-6);
  ScanOptions o;
  o.mode = FeedforwardMode::kPi;
  const ScanRun plain = run_scan(experiment, models, line, o);
  ASSERT_FALSE(plain.refused) << plain.reason;
  EXPECT_GT(plain.stats.rms_true_m, 3e-9);  // the model's error for these loops
  o.learning = true;
  const ScanRun learned = run_scan(experiment, models, line, o);
  ASSERT_FALSE(learned.refused) << learned.reason;
  EXPECT_LE(learned.stats.rms_true_m, 1e-9);
  EXPECT_LE(learned.stats.max_abs_true_m, 5e-9);
  EXPECT_GE(learned.periods_to_converge, 0);
  EXPECT_LE(learned.periods_to_converge, 20);
  EXPECT_EQ(learned.clamped_ticks, 0u);
  EXPECT_EQ(learned.counters.u_slew_clamped + learned.counters.u_clamped, 0u);
}

TEST(Scan, TheStageInverseIsWhatMakesTheFastLinesTrack) {
  // Without it a 50 Hz line is several times worse: the 1.72 kHz stage and the hold lag a third
  // of a tick behind the plan.
  const TrackingExperiment experiment;
  const ScanReference line = scan_references()[3];  // sine 50 Hz 1 um
  const IdentifiedModels models = identify_for_scan(experiment, line.amplitude_m);
  ScanOptions o;
  const ScanRun with = run_scan(experiment, models, line, o);
  o.stage_inverse = false;
  const ScanRun without = run_scan(experiment, models, line, o);
  ASSERT_FALSE(with.refused || without.refused);
  EXPECT_GT(without.stats.rms_true_m, 1.2 * with.stats.rms_true_m);
}

// Behind the two-mode stage (1.5 ticks of delay), a hysteresis fitted u -> y carries the stage's
// lag and delay as width, and the compensator, inverting the stage with its delay, corrects them
// twice: ~6 nm at every line rate. Fitted on the samples with the stage taken out it does not.
TEST(Scan, BehindALinearStageTheHysteresisIsFittedWithoutIt) {
  const TrackingExperiment experiment = two_mode_experiment();
  ScanOptions o;
  o.servo = false;                        // tuned for Banning's stage
  for (const std::size_t i : {2u, 4u}) {  // sine 10 Hz 1 um, sine 100 Hz 0.5 um
    const ScanReference line = scan_references()[i];
    const IdentifiedModels raw = identify_for_scan(experiment, line.amplitude_m);
    const IdentifiedModels removed = identify_for_scan(experiment, line.amplitude_m, scan_stage(experiment, o));
    o.mode = FeedforwardMode::kPi;  // the same model for both
    const ScanRun as_measured = run_scan(experiment, raw, line, o);
    const ScanRun stage_removed = run_scan(experiment, removed, line, o);
    ASSERT_FALSE(as_measured.refused || stage_removed.refused) << line.name;
    EXPECT_GT(as_measured.stats.rms_true_m, 3e-9) << line.name;
    EXPECT_LT(stage_removed.stats.rms_true_m, 0.6 * as_measured.stats.rms_true_m)
        << line.name;  // 1.9 / 5.9, 1.8 / 3.5 nm
  }
}

// A model whose gain is 1.5 times the stage's, beside the two-mode stage's own servo (the integral
// servo with two notches of deploy/config/two-mode): the servo pushes along the feedforward where
// the 50 Hz triangle is fastest, by several times its slew reserve. Learning takes the feedforward
// up to the plan's limit; the corrections are held to what the servo's recent steps leave, so the
// bridge clamps nothing (it clamped 28 ticks when they were held to the plan's share alone).
TEST(Scan, LearningLeavesTheServoItsStepsBesideAModelFarOffInGain) {
  const TrackingExperiment experiment = two_mode_experiment();
  const ScanReference line = scan_references()[1];  // triangle 50 Hz 1 um
  ASSERT_EQ(line.frequency_hz, 50.0);
  ScanOptions o;
  o.kp = 0.0;
  o.ki = 800.0;
  o.notch_hz = 780.0;
  o.notch_q = 0.34;
  o.notch2_hz = 2400.0;
  o.notch2_q = 3.0;
  o.mode = FeedforwardMode::kPi;
  IdentifiedModels models = identify_for_scan(experiment, line.amplitude_m, scan_stage(experiment, o));
  for (double& w : models.pi.weights) w *= 1.5;
  const ScanRun off = run_scan(experiment, models, line, o);
  o.learning = true;
  const ScanRun on = run_scan(experiment, models, line, o);
  ASSERT_FALSE(off.refused || on.refused);
  EXPECT_EQ(off.clamped_ticks, 0u);
  EXPECT_EQ(on.clamped_ticks, 0u);
  EXPECT_LT(on.stats.rms_true_m, 0.5 * off.stats.rms_true_m);  // measured 97.6 against 235.7 nm
}

// Learning beside the two-mode stage's inverse, with its true model and with deliberately wrong
// ones: with a filter past the stage's anti-resonance (1.85 kHz, where the inverse's gain is ~100)
// the 10 Hz triangle ran away to the correction bound (30 nm, 185 nm max); learned only below 0.7
// of the lowest mode (learning_for_stage) it converges, and a wrong model never makes a period
// worse than without learning, nor clamps.
TEST(Scan, LearningBesideALinearStageConvergesEvenWithAWrongModel) {
  const TrackingExperiment experiment = two_mode_experiment();
  const double delay_s = experiment.series_stage.delay_s;
  const ScanReference line = scan_references()[0];  // triangle 10 Hz 1 um
  ASSERT_EQ(line.shape, TrajectoryShape::kTriangle);
  struct Case {
    const char* name;
    LinearStageSpec model;
    double converged_m;  // the learned line's RMS bound (measured: 0.45, 0.41, 0.48 nm)
  };
  const Case cases[] = {
      {"true", experiment.series_stage, 1e-9},
      {"mode 10 % high", LinearStageSpec::sum_of_modes({{858.0, 0.03, 0.92}, {2400.0, 0.02, 0.08}}, delay_s), 1e-9},
      {"a tick of delay left out",
       LinearStageSpec::sum_of_modes({{780.0, 0.03, 0.92}, {2400.0, 0.02, 0.08}}, delay_s - 1e-4), 1e-9},
  };
  for (const Case& c : cases) {
    ScanOptions o;
    o.servo = false;
    o.stage_model = c.model;
    o.mode = FeedforwardMode::kPi;
    const IdentifiedModels models = identify_for_scan(experiment, line.amplitude_m, scan_stage(experiment, o));
    const ScanRun off = run_scan(experiment, models, line, o);
    o.learning = true;
    const ScanRun on = run_scan(experiment, models, line, o);
    ASSERT_FALSE(off.refused || on.refused) << c.name;
    EXPECT_LT(on.stats.rms_true_m, c.converged_m) << c.name;
    EXPECT_EQ(on.clamped_ticks, 0u) << c.name;
    EXPECT_EQ(on.counters.learning_held, 0u) << c.name;
    ASSERT_EQ(on.rms_per_period_m.size(), off.rms_per_period_m.size());
    for (std::size_t p = 0; p < on.rms_per_period_m.size(); ++p)
      EXPECT_LE(on.rms_per_period_m[p], 1.1 * off.rms_per_period_m[p]) << c.name << ", period " << p;
  }
}

TEST(Scan, TheLearningFilterStaysBelowALinearStagesLowestModeOrAntiResonance) {
  const double dt_s = 1e-4;
  StageModel stage;
  EXPECT_EQ(learning_for_stage(default_learning(), stage, dt_s).cutoff_hz, 2000.0);  // none: as configured
  stage.kind = StageModel::Kind::kSecondOrder;                                       // Banning's: as configured
  EXPECT_EQ(learning_for_stage(default_learning(), stage, dt_s).cutoff_hz, 2000.0);
  stage.kind = StageModel::Kind::kLinear;
  stage.linear = two_mode_experiment().series_stage;
  EXPECT_NEAR(lowest_linear_feature_hz(stage, dt_s), 780.0 * std::sqrt(1.0 - 0.03 * 0.03), 0.5);
  EXPECT_NEAR(learning_for_stage(default_learning(), stage, dt_s).cutoff_hz, 0.7 * 780.0, 0.5);
  // A lightly damped zero pair (an anti-resonance) below the mode sets it: the sampled model's, which
  // the hold moves by under 1 % from the continuous one's (poles map exactly, zeros do not).
  stage.linear = LinearStageSpec::zero_pole({{-15.0, 300.0}}, {{-45.0, 900.0}, {-3000.0, 0.0}, {-3000.0, 0.0}});
  EXPECT_NEAR(lowest_linear_feature_hz(stage, dt_s), std::hypot(15.0, 300.0), 3.0);
  // A configured cutoff below it stays.
  LearningConfig low = default_learning();
  low.cutoff_hz = 100.0;
  EXPECT_EQ(learning_for_stage(low, stage, dt_s).cutoff_hz, 100.0);
  // A band the stage's identification measured the model in takes learning further (0.7 of it),
  // never past the configured cutoff, and never below the lowest mode's share.
  stage.linear = two_mode_experiment().series_stage;
  stage.known_to_hz = 1220.0;
  EXPECT_NEAR(learning_for_stage(default_learning(), stage, dt_s).cutoff_hz, 0.7 * 1220.0, 1e-9);
  stage.known_to_hz = 5000.0;
  EXPECT_EQ(learning_for_stage(default_learning(), stage, dt_s).cutoff_hz, 2000.0);
  stage.known_to_hz = 300.0;
  EXPECT_NEAR(learning_for_stage(default_learning(), stage, dt_s).cutoff_hz, 0.7 * 780.0, 0.5);
}

TEST(Scan, AnInfeasibleLineIsRefusedNamingTheSlewLimit) {
  const TrackingExperiment experiment;
  const IdentifiedModels models = identify_for_scan(experiment, 1e-6);
  ScanOptions refuse;
  refuse.shape_if_infeasible = false;
  for (const double f : {100.0, 200.0}) {  // 1 um at 100 Hz needs ~1e5 V/s, twice the limit
    const ScanRun run = run_scan(experiment, models, {"sine 1 um", TrajectoryShape::kSine, 1e-6, f}, refuse);
    EXPECT_TRUE(run.refused) << f;
    EXPECT_NE(run.reason.find("actuator.slew_V_per_s"), std::string::npos) << run.reason;
  }
  // Past the tracking share but inside the plan's: refused for the servo's reserve.
  const ScanReference fast = scan_references().back();  // sine 200 Hz 0.25 um
  ASSERT_DOUBLE_EQ(fast.frequency_hz, 200.0);
  const ScanRun run = run_scan(experiment, identify_for_scan(experiment, fast.amplitude_m), fast, refuse);
  EXPECT_TRUE(run.refused);
  EXPECT_NE(run.reason.find("compensator.servo_slew_reserve"), std::string::npos) << run.reason;
  EXPECT_NE(run.reason.find("largest feasible amplitude"), std::string::npos) << run.reason;
}

// A parameter swap re-anchors the model at the measured position. Measured over the first ticks
// after the swap's reversal, the error there (a triangle's corner behind a lightly damped mode) was
// read as an offset and kept: a swap of the very set in use took the 10 Hz triangle on the
// two-mode stage from 1.8 to 4.3 nm for the rest of the line. Over a whole period it averages out.
TEST(Scan, ASwapOfTheSetInUseLeavesTheTrackingAsItWas) {
  const TrackingExperiment e = two_mode_experiment();
  ScanOptions o;
  o.servo = false;
  o.learning = false;
  o.mode = FeedforwardMode::kPi;
  for (const std::size_t i : {0u, 4u}) {  // triangle 10 Hz 1 um, sine 100 Hz 0.5 um
    const ScanReference line = scan_references()[i];
    const IdentifiedModels m = identify_for_scan(e, line.amplitude_m, scan_stage(e, o));
    double rms_m[2] = {0.0, 0.0};
    for (const bool swap : {false, true}) {
      LoopSimulation sim(scan_loop_config(e, m, o));
      TrajectorySpec spec;
      spec.shape = line.shape;
      spec.amplitude_m = line.amplitude_m;
      spec.frequency_hz = line.frequency_hz;
      spec.blend_s = 0.2;
      sim.run(0.05);
      sim.compensator().take_trajectory(spec, 0.3);
      sim.run(0.95);
      if (swap) {
        ModelParamSet p;
        p.kind = ModelKind::pi;
        p.pi = m.pi;
        sim.compensator().offer_model(p, 7);
      }
      sim.run(1.0);
      rms_m[swap ? 1 : 0] = sim.tracking(1.5, 2.0).rms_true_m;
      EXPECT_EQ(sim.compensator().counters().reanchors, swap ? 1u : 0u) << line.name;
    }
    EXPECT_LT(rms_m[1], 1.05 * rms_m[0]) << line.name << ": " << rms_m[0] * 1e9 << " nm without the swap";
  }
}

}  // namespace
}  // namespace hystloop
