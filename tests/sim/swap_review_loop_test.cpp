// A set swapped in on a line that tracks the line worse than the set before is taken back
// (loop/swap_review.hpp), on Banning's stage and behind the two-mode stage with its own servo: the
// live failure was a PI refit whose window held the end of one line and the start of the next,
// which took a 100 Hz sine from 2.5 to 11.7 nm until the line ended.
#include <gtest/gtest.h>

#include <string>

#include "sim/scan_experiment.hpp"

namespace hystloop {
namespace {

struct Plant {
  std::string name;
  TrackingExperiment experiment;
  ScanOptions options;
};

std::vector<Plant> plants() {
  ScanOptions banning;
  banning.mode = FeedforwardMode::kPi;
  ScanOptions two_mode = banning;  // deploy/config/two-mode's servo
  two_mode.kp = 0.0;
  two_mode.ki = 800.0;
  two_mode.notch_hz = 780.0;
  two_mode.notch_q = 0.34;
  two_mode.notch2_hz = 2400.0;
  two_mode.notch2_q = 3.0;
  return {{"Banning's stage", TrackingExperiment{}, banning}, {"two modes", two_mode_experiment(), two_mode}};
}

// The 100 Hz 0.5 um sine from 0.3 s (approached over 0.2 s), after 0.05 s of the loop.
void start_line(LoopSimulation& sim) {
  TrajectorySpec spec;
  spec.shape = TrajectoryShape::kSine;
  spec.amplitude_m = 0.5e-6;
  spec.frequency_hz = 100.0;
  spec.blend_s = 0.2;
  sim.run(0.05);
  sim.compensator().take_trajectory(spec, 0.3);
}

// The identified PI set 10 % off in gain: a refit across two lines' loops errs by as much and more.
ModelParamSet pi_off_in_gain(const IdentifiedModels& models) {
  ModelParamSet bad;
  bad.kind = ModelKind::pi;
  bad.pi = models.pi;
  for (double& w : bad.pi.weights) w *= 1.1;
  return bad;
}

struct LineRun {
  double rms_m = 0.0;  // true, over the last 0.5 s
  CompensatorCounters counters;
};

// The 100 Hz 0.5 um sine with the set identified for it; at 1.0 s, `offered` (when given) is
// offered as the re-identifier's next set.
LineRun run_line(const Plant& plant, const IdentifiedModels& models, const std::optional<ModelParamSet>& offered,
                 double worse_ratio) {
  LoopSimulationConfig config = scan_loop_config(plant.experiment, models, plant.options);
  config.compensator.swap_review.worse_ratio = worse_ratio;
  LoopSimulation sim(config);
  start_line(sim);
  sim.run(0.95);
  if (offered) sim.compensator().offer_model(*offered, 7);
  sim.run(1.5);
  return {sim.tracking(2.0, 2.5).rms_true_m, sim.compensator().counters()};
}

TEST(SwapReview, ASetThatTracksTheLineWorseIsTakenBackAndOneThatTracksItAsWellIsKept) {
  for (const Plant& plant : plants()) {
    const IdentifiedModels models =
        identify_for_scan(plant.experiment, 0.5e-6, scan_stage(plant.experiment, plant.options));
    const LineRun none = run_line(plant, models, std::nullopt, 1.5);
    EXPECT_EQ(none.counters.swaps_reviewed, 0u) << plant.name;

    const ModelParamSet bad = pi_off_in_gain(models);
    const LineRun kept_bad = run_line(plant, models, bad, 0.0);  // no review: what the swap does
    // Measured: 0.66 -> 8.2 nm on Banning's stage, 1.6 -> 36 nm behind the two modes.
    EXPECT_GT(kept_bad.rms_m, 2.0 * none.rms_m) << plant.name << ": " << none.rms_m * 1e9 << " nm without a swap";
    EXPECT_EQ(kept_bad.counters.swaps_reviewed, 0u) << plant.name;
    const LineRun reviewed = run_line(plant, models, bad, 1.5);
    EXPECT_EQ(reviewed.counters.swaps_reviewed, 1u) << plant.name;
    EXPECT_EQ(reviewed.counters.swaps_taken_back, 1u) << plant.name;
    EXPECT_EQ(reviewed.counters.params_swapped, 2u) << plant.name;  // in, and back
    EXPECT_LT(reviewed.rms_m, 1.1 * none.rms_m) << plant.name << ": " << none.rms_m * 1e9 << " nm without a swap, "
                                                << kept_bad.rms_m * 1e9 << " nm keeping the worse set";

    // The set in use, offered again: reviewed and kept.
    ModelParamSet same;
    same.kind = ModelKind::pi;
    same.pi = models.pi;
    const LineRun kept = run_line(plant, models, same, 1.5);
    EXPECT_EQ(kept.counters.swaps_reviewed, 1u) << plant.name;
    EXPECT_EQ(kept.counters.swaps_taken_back, 0u) << plant.name;
    EXPECT_LT(kept.rms_m, 1.1 * none.rms_m) << plant.name;
  }
}

// A set offered before the line has run its approach and a period has nothing to be held against:
// swapped in and not judged.
TEST(SwapReview, ASwapBeforeTheLineHasSettledIsNotJudged) {
  const Plant plant = plants()[0];
  const IdentifiedModels models =
      identify_for_scan(plant.experiment, 0.5e-6, scan_stage(plant.experiment, plant.options));
  LoopSimulation sim(scan_loop_config(plant.experiment, models, plant.options));
  start_line(sim);
  const ModelParamSet bad = pi_off_in_gain(models);
  sim.compensator().offer_model(bad, 7);
  sim.run(1.0);
  EXPECT_EQ(sim.compensator().counters().params_swapped, 1u);
  EXPECT_EQ(sim.compensator().counters().swaps_reviewed, 0u);
}

// A mode the operator sets while a swap is under review stands: the review ends without a verdict
// and nothing switches the model back.
TEST(SwapReview, AModeSetByHandDuringAReviewIsNotTakenBack) {
  const Plant plant = plants()[0];
  const IdentifiedModels models =
      identify_for_scan(plant.experiment, 0.5e-6, scan_stage(plant.experiment, plant.options));
  LoopSimulation sim(scan_loop_config(plant.experiment, models, plant.options));
  start_line(sim);
  sim.run(0.95);
  const ModelParamSet bad = pi_off_in_gain(models);
  sim.compensator().offer_model(bad, 7);
  // Swapped in at the reversal at ~1.0025 s; its window after ends ~0.2 s later and is planned 50 ms
  // ahead: at 1.18 s all of it is planned and the verdict not yet due.
  sim.run(0.18);
  ASSERT_EQ(sim.compensator().counters().swaps_reviewed, 1u);
  ASSERT_EQ(sim.compensator().counters().swaps_taken_back, 0u);
  sim.compensator().set_mode(FeedforwardMode::kKatalenic);
  sim.run(1.0);
  EXPECT_EQ(sim.compensator().counters().swaps_taken_back, 0u);
  EXPECT_EQ(sim.compensator().mode(), FeedforwardMode::kKatalenic);
}

}  // namespace
}  // namespace hystloop
