// read_reident_options: defaults, the shared mem: snippet, and refusals that name the field.
#include "reidentifier/reident_options.hpp"

#include <gtest/gtest.h>

#include <string>
#include <string_view>
#include <vector>

#include "core/errors.hpp"
#include "models/model_descriptors.hpp"
#include "runtime/stage_config.hpp"

namespace hystloop {
namespace {

std::string refusal(const std::string& yaml) {
  try {
    read_reident_options(Config::from_string(yaml, "r.yaml"));
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(ReidentOptions, DefaultsAreTheEstimatorsAtTenKilohertz) {
  const ReidentOptions o = read_reident_options(Config());
  EXPECT_EQ(o.estimator.window_samples, 20000u);
  EXPECT_EQ(o.estimator.capacity_samples, 100000u);
  EXPECT_EQ(o.estimator.holdout_branches, 1u);
  EXPECT_DOUBLE_EQ(o.refit_period_s, 1.0);
  EXPECT_FALSE(o.publish_invalid);
  EXPECT_GE(o.lcm_queue, 1000);
  EXPECT_DOUBLE_EQ(o.initial.c1, MemParams::paper_like().c1);
}

TEST(ReidentOptions, ReadsTheSharedMemSnippetAndTheReidentSection) {
  const ReidentOptions o = read_reident_options(Config::from_string(
      "mem: {c1: 4.0e-9, c2: 2.0e-12, c3: 0.8}\n"
      "compensator: {anything: 1}\n"
      "reidentifier: {rate_hz: 5000, window_s: 1.5, capacity_s: 3, refit_period_s: 0.5, holdout_branches: 2,\n"
      "          min_relative_improvement: 0.05, max_residual_rms_m: 1.0e-8, max_solver_time_s: 0.02,\n"
      "          publish_invalid: true, stale_after_s: 2, degraded_after_poisoned: 5, lcm_queue: 5000}\n"));
  EXPECT_DOUBLE_EQ(o.initial.c1, 4.0e-9);
  EXPECT_DOUBLE_EQ(o.initial.c2, 2.0e-12);
  EXPECT_DOUBLE_EQ(o.initial.c3, 0.8);
  EXPECT_EQ(o.estimator.window_samples, 7500u);
  EXPECT_EQ(o.estimator.capacity_samples, 15000u);
  EXPECT_EQ(o.estimator.holdout_branches, 2u);
  EXPECT_DOUBLE_EQ(o.estimator.min_relative_improvement, 0.05);
  EXPECT_DOUBLE_EQ(o.estimator.max_residual_rms_m, 1e-8);
  EXPECT_DOUBLE_EQ(o.estimator.fit.max_solver_time_s, 0.02);
  EXPECT_DOUBLE_EQ(o.refit_period_s, 0.5);
  EXPECT_TRUE(o.publish_invalid);
  EXPECT_EQ(o.degraded_after_poisoned, 5);
  EXPECT_EQ(o.lcm_queue, 5000);
}

TEST(ReidentOptions, RefusalsNameTheField) {
  EXPECT_NE(refusal("reidentifier: {refit_period_s: -1}").find("r.yaml: reidentifier.refit_period_s:"),
            std::string::npos);
  EXPECT_NE(refusal("reidentifier: {window_s: 0.001}").find("reidentifier.window_s: must hold at least 16"),
            std::string::npos);
  EXPECT_NE(refusal("reidentifier: {window_s: 5, capacity_s: 2}")
                .find("reidentifier.capacity_s: must be >= reidentifier.window_s"),
            std::string::npos);
  EXPECT_NE(refusal("reidentifier: {holdout_branches: 0}").find("reidentifier.holdout_branches"), std::string::npos);
  EXPECT_NE(refusal("reidentifier: {min_relative_improvement: 1.5}").find("reidentifier.min_relative_improvement"),
            std::string::npos);
  EXPECT_NE(refusal("reidentifier: {lcm_queue: 10}").find("reidentifier.lcm_queue"), std::string::npos);
  EXPECT_NE(refusal("reidentifier: {publish_invalid: maybe}").find("reidentifier.publish_invalid"), std::string::npos);
  EXPECT_NE(refusal("mem: {c1: -1.0e-9}").find("mem.c1: must be > 0"), std::string::npos);
  EXPECT_NE(refusal("mem: {c2: -1.0e-9}").find("mem.c2"), std::string::npos);
  EXPECT_NE(refusal("mem: {c3: 0}").find("mem.c3"), std::string::npos);
  const std::string typo = refusal("reidentifier: {refit_period: 2}");
  EXPECT_NE(typo.find("reidentifier.refit_period: unknown key"), std::string::npos) << typo;
  EXPECT_NE(typo.find("reidentifier.refit_period_s"), std::string::npos) << typo;
}

// The model choice's refusals list the models from the registry (models/model_set.hpp): every
// online model, so one added there is named without editing the message.
TEST(ReidentOptions, ModelChoiceRefusalsListEveryOnlineModel) {
  const std::string models = refusal("reidentifier: {models: \"mem,foo\"}");
  const std::string pin = refusal("reidentifier: {pin_model: foo}");
  EXPECT_NE(models.find("reidentifier.models: expected off, auto or a comma-separated list of models, each " +
                        choice_list(model_kind_names()) + " (got \"foo\")"),
            std::string::npos)
      << models;
  std::vector<std::string_view> pins{"none"};
  for (const std::string_view name : model_kind_names()) pins.push_back(name);
  EXPECT_NE(pin.find("reidentifier.pin_model: expected " + choice_list(pins) + " (got \"foo\")"), std::string::npos)
      << pin;
  for (const std::string_view name : model_kind_names()) {
    EXPECT_EQ(refusal("reidentifier: {pin_model: " + std::string(name) + "}"), "accepted") << name;
  }
}

// mem: is read through the MEM's parameter table, as the compensator reads it: every key (and
// alias) of the table is taken, anything else under mem: is refused naming the key.
TEST(ReidentOptions, TheMemSectionIsTheTables) {
  const MemParams d = MemParams::paper_like();
  for (const auto& row : MemDescriptor::table()) {
    for (const std::string_view name : {row.name, row.alias}) {
      if (name.empty()) continue;
      const std::string yaml = "mem: {" + std::string(name) + ": " + row.show(d) + "}\n";
      EXPECT_EQ(refusal(yaml), "accepted") << yaml;
    }
  }
  const std::string unknown = refusal("mem: {c4: 1.0e-9}");
  EXPECT_NE(unknown.find("r.yaml: mem.c4: unknown parameter 'c4' of model mem"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("(valid: c1, c2, c3)"), std::string::npos) << unknown;
  const std::string malformed = refusal("mem: {c1: 5e-9x}");
  EXPECT_NE(malformed.find("r.yaml: mem.c1: expected a number, got '5e-9x'"), std::string::npos) << malformed;
  EXPECT_DOUBLE_EQ(read_reident_options(Config::from_string("mem: {c2: 3.0e-12}\n")).initial.c2, 3.0e-12);
  EXPECT_DOUBLE_EQ(read_reident_options(Config::from_string("mem: {c2: 3.0e-12}\n")).initial.c1, d.c1);
}

TEST(ReidentOptions, TheDeployedDefaultsLoad) {
  const ReidentOptions o =
      read_reident_options(Config::load_file(std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/reidentifier.yaml"));
  const ReidentOptions d = read_reident_options(Config());
  EXPECT_EQ(o.estimator.window_samples, d.estimator.window_samples);
  EXPECT_EQ(o.estimator.capacity_samples, d.estimator.capacity_samples);
  // The initial set is the compensator's (one snippet configures both), not the code's default.
  const Config compensator = Config::load_file(std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/compensator.yaml");
  EXPECT_DOUBLE_EQ(o.initial.c1, compensator.get<double>("mem.c1"));
  EXPECT_DOUBLE_EQ(o.initial.c2, compensator.get<double>("mem.c2"));
  EXPECT_DOUBLE_EQ(o.initial.c3, compensator.get<double>("mem.c3"));
  EXPECT_DOUBLE_EQ(o.refit_period_s, d.refit_period_s);
  EXPECT_EQ(o.lcm_queue, d.lcm_queue);
}

// The stage the re-identifier takes out of the samples must be the one the compensator inverts:
// a fit on samples with the stage left in (or taken out twice) is the stage's lag read as hysteresis.
TEST(ReidentOptions, TheDeployedStageIsTheCompensators) {
  const std::string root = std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/";
  Config scan = Config::load_file(root + "reidentifier.yaml");
  scan.layer(Config::load_file(root + "scan/reidentifier.layer.yaml"));  // as deploy/hystloop scan runs it
  const Config compensator = Config::load_file(root + "compensator.yaml");
  for (const Config& config : {Config::load_file(root + "reidentifier.yaml"), scan}) {
    const ReidentOptions o = read_reident_options(config);
    EXPECT_TRUE(o.stage.has_dynamics());
    EXPECT_EQ(compensator.get<std::string>("stage.kind"), "second_order");
    EXPECT_DOUBLE_EQ(o.stage.second_order.k, compensator.get<double>("stage.k"));
    EXPECT_DOUBLE_EQ(o.stage.second_order.c, compensator.get<double>("stage.c"));
  }
  EXPECT_TRUE(read_reident_options(scan).models.enabled);  // the scan chooses the model
}

// A scan's layer changes the re-identifier's model choice, never the stage it takes out: over the
// two-mode rig's config the stage is the two-mode stage its compensator inverts.
TEST(ReidentOptions, TheScansLayerKeepsTheRigsStage) {
  const std::string root = std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/";
  const Config layer = Config::load_file(root + "scan/reidentifier.layer.yaml");
  for (const std::string& key : layer.keys()) EXPECT_EQ(key.rfind("reidentifier.", 0), 0u) << key;
  Config two_mode = Config::load_file(root + "two-mode/reidentifier.yaml");
  two_mode.layer(layer);
  const ReidentOptions o = read_reident_options(two_mode);
  const StageModel compensator =
      read_stage_model(Config::load_file(root + "two-mode/compensator.yaml"), StageModel{}, 1e-4);
  EXPECT_EQ(o.stage.kind, StageModel::Kind::kLinear);
  EXPECT_EQ(o.stage.linear.delay_s, compensator.linear.delay_s);
  EXPECT_EQ(o.stage.linear.modes.size(), 2u);
}

// The hardware example publishes nothing until an operator releases it, and judges refits against
// the actuator and the gain the compensator's hardware config gives.
TEST(ReidentOptions, TheHardwareExampleHoldsItsRefitsAndSharesTheCompensatorsNumbers) {
  const std::string root = std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/hardware/";
  const ReidentOptions o = read_reident_options(Config::load_file(root + "reidentifier.yaml"));
  const Config compensator = Config::load_file(root + "compensator.yaml");
  EXPECT_TRUE(o.hold);
  EXPECT_EQ(o.plausibility.u_min_V, compensator.get<double>("actuator.u_min_V"));
  EXPECT_EQ(o.plausibility.u_max_V, compensator.get<double>("actuator.u_max_V"));
  EXPECT_EQ(o.plausibility.nominal_gain_m_per_V, compensator.get<double>("linear.gain"));
  EXPECT_FALSE(o.stage.has_dynamics());
}

// One re-identifier per axis: reidentifier.axis names it as hystloop-ctl's --axis does.
TEST(ReidentOptions, TheAxisIsXByDefaultAndNamedXYOrZ) {
  EXPECT_EQ(read_reident_options(Config()).axis, 0);
  EXPECT_EQ(read_reident_options(Config::from_string("reidentifier: {axis: x}\n")).axis, 0);
  EXPECT_EQ(read_reident_options(Config::from_string("reidentifier: {axis: y}\n")).axis, 1);
  EXPECT_EQ(read_reident_options(Config::from_string("reidentifier: {axis: z}\n")).axis, 2);
  const ReidentOptions deployed =
      read_reident_options(Config::load_file(std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/reidentifier.yaml"));
  EXPECT_EQ(deployed.axis, 0);
  for (const char* bad : {"w", "1", "X", "xy"}) {
    const std::string why = refusal("reidentifier: {axis: " + std::string(bad) + "}\n");
    EXPECT_NE(why.find("r.yaml: reidentifier.axis: expected x, y or z"), std::string::npos) << why;
  }
}

TEST(ReidentOptions, ReadsAndChecksTheStage) {
  EXPECT_FALSE(read_reident_options(Config()).stage.has_dynamics()) << "none by default: samples as measured";
  const ReidentOptions o = read_reident_options(
      Config::from_string("stage: {kind: second_order, k: 2.0e8, c: 3.0e3, order: stage_then_hysteresis}\n"));
  EXPECT_TRUE(o.stage.has_dynamics());
  EXPECT_DOUBLE_EQ(o.stage.second_order.k, 2.0e8);
  EXPECT_DOUBLE_EQ(o.stage.second_order.c, 3.0e3);
  EXPECT_EQ(o.stage.order, BanningOrder::kStageThenHysteresis);
  EXPECT_NE(refusal("stage: {kind: third_order}").find("stage.kind: must be none, second_order or linear"),
            std::string::npos);
  EXPECT_NE(refusal("stage: {kind: second_order, k: -1}").find("stage.k"), std::string::npos);
  EXPECT_NE(refusal("stage: {k: 1.0e8}").find("stage.kind: is none"), std::string::npos);
  EXPECT_NE(refusal("stage: {kind: second_order, order: sideways}").find("stage.order"), std::string::npos);
}

// The two-mode example's re-identifier takes out the stage its compensator inverts (the same
// modes and delay), not Banning's: fitted behind it, the hysteresis would carry its lag as width.
TEST(ReidentOptions, TheTwoModeExampleRemovesTheStageItsCompensatorInverts) {
  const std::string dir = std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/two-mode/";
  const ReidentOptions o = read_reident_options(Config::load_file(dir + "reidentifier.yaml"));
  const Config compensator = Config::load_file(dir + "compensator.yaml");
  ASSERT_TRUE(o.stage.is_linear());
  ASSERT_EQ(o.stage.linear.modes.size(), 2u);
  EXPECT_EQ(o.stage.linear.modes[0].frequency_hz, 780.0);
  EXPECT_EQ(o.stage.linear.modes[1].frequency_hz, 2400.0);
  EXPECT_EQ(o.stage.linear.delay_s, compensator.get<double>("stage.delay_s", 0.0));
}

}  // namespace
}  // namespace hystloop
