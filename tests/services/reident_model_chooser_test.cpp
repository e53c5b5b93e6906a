// The re-identifier's online model choice (ModelChooser) with the worker stepped by hand: off by
// default (MEM refits only, nothing on HX_MODEL); pinned to a kind not in use, the next selection
// fits that kind and switches to it once, numbered in the core's one version sequence, and the MEM
// refits stop while it is in use; a poisoned window proposes nothing; the config keys are checked.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/config.hpp"
#include "core/errors.hpp"
#include "reident/model_chooser.hpp"
#include "reident/reident_core.hpp"
#include "reidentifier/reident_options.hpp"
#include "models/linear.hpp"
#include "reident_test_data.hpp"

namespace hystloop {
namespace {

constexpr std::int64_t kSecond = 1'000'000;

ModelParamSet mem_set(const MemParams& p) {
  ModelParamSet s;
  s.mem = p;
  return s;
}

struct Rig {
  MemParams truth = testdata::piezo_truth();
  ReidentOptions options = testdata::small_reident_options(truth);
  ReidentCore core{options, "reident@test", /*start_thread=*/false};
  std::int64_t seq = 0;
  std::int64_t now = 10 * kSecond;
  sensor_block_t block = testdata::reserved_sensor_block();
  testdata::SineRecord record = testdata::sine_record(truth, 3, 2.0);

  void stream(double seconds, bool poison = false) {
    const auto n = static_cast<std::size_t>(std::llround(seconds * 1e4));
    for (std::size_t k = 0; k < n; k += 10) {
      testdata::fill_sensor_block(block, seq, now, record.u, record.y, k % (record.u.size() - 10), 10);
      core.on_sensor_block(block, now);
      seq += 10;
      now += 1000;
    }
    if (poison) core.on_refused_block(10, now);
  }
};

ModelChoiceOptions enabled(std::optional<ModelKind> pinned = std::nullopt) {
  ModelChoiceOptions o;
  o.enabled = true;
  o.period_s = 1.0;
  o.pinned = pinned;
  o.selector.decimation = 5;
  return o;
}

TEST(ReidentModelChooser, OffByDefaultItNeverProposes) {
  Rig r;
  ModelChooser chooser(ModelChoiceOptions{}, mem_set(r.truth), r.core.estimator().make_window(), false);
  r.stream(0.6);
  EXPECT_EQ(chooser.poll(r.core, r.now).kind, ModelDecision::Kind::none);
  EXPECT_FALSE(chooser.run_pending());  // nothing was submitted
}

TEST(ReidentModelChooser, PinnedToAnotherKindSwitchesToItOnceWithTheNextVersion) {
  Rig r;
  ModelChooser chooser(enabled(ModelKind::linear), mem_set(r.truth), r.core.estimator().make_window(), false);
  r.stream(0.6);
  EXPECT_EQ(chooser.poll(r.core, r.now).kind, ModelDecision::Kind::none);  // submitted
  ASSERT_TRUE(chooser.run_pending());
  const std::int32_t before = r.core.in_use().highest_seen();
  const ModelDecision d = chooser.poll(r.core, r.now);
  ASSERT_EQ(d.kind, ModelDecision::Kind::change) << chooser.last_reason();
  EXPECT_EQ(d.params.kind, ModelKind::linear);
  EXPECT_NO_THROW(d.params.validate());
  EXPECT_GT(d.version, before);
  EXPECT_EQ(chooser.in_use().kind, ModelKind::linear);
  EXPECT_FALSE(r.core.mem_refits());  // MEM is not in use: HX_PARAMS stays quiet
  EXPECT_EQ(chooser.count(ModelChooser::changes), 1u);

  // Pinned to the model in use: never a different model again.
  r.stream(0.6);
  r.now += 2 * kSecond;
  chooser.poll(r.core, r.now);
  ASSERT_TRUE(chooser.run_pending());
  const ModelDecision next = chooser.poll(r.core, r.now);
  EXPECT_NE(next.kind, ModelDecision::Kind::change);
  EXPECT_EQ(chooser.in_use().kind, ModelKind::linear);
}

TEST(ReidentModelChooser, APoisonedWindowProposesNothing) {
  Rig r;
  ModelChooser chooser(enabled(ModelKind::linear), mem_set(r.truth), r.core.estimator().make_window(), false);
  r.stream(0.3);
  r.stream(0.3, /*poison=*/true);
  chooser.poll(r.core, r.now);
  ASSERT_TRUE(chooser.run_pending());
  EXPECT_EQ(chooser.poll(r.core, r.now).kind, ModelDecision::Kind::none);
  EXPECT_EQ(chooser.count(ModelChooser::poisoned), 1u);
  EXPECT_TRUE(r.core.mem_refits());
}

// A window across two regimes: here small loops (20 V), then the major loop (250 V), which a
// linear model explains far worse. The first refits on the big loops are more than
// regime_factor x worse than the recent ones: not published, counted; once every window is of the
// new regime the median follows it and the refit is published. With the factor 0, at once.
TEST(ReidentModelChooser, ARefitAcrossAChangeOfRegimeWaitsUntilTheRegimeLasts) {
  for (const double factor : {3.0, 0.0}) {
    SCOPED_TRACE(factor);
    Rig r;
    testdata::SineRecord small;
    small.u = testdata::sine_input(20.0, 10.0, 1e4, 2.0);
    small.y = testdata::mem_branches(small.u, r.truth);
    testdata::add_noise(small.y, 1e-9, 5);
    const testdata::SineRecord big = r.record;
    r.record = small;
    ModelChoiceOptions o = enabled(ModelKind::linear);
    o.selector.selection.candidates = {ModelKind::linear};
    o.regime_factor = factor;
    ModelParamSet linear;
    linear.kind = ModelKind::linear;
    linear.mem = r.truth;
    linear.linear = linear_params_from_mem(r.truth, 250.0);
    ModelChooser chooser(o, linear, r.core.estimator().make_window(), false);
    auto select = [&] {
      r.stream(0.6);
      r.now += 2 * kSecond;
      chooser.poll(r.core, r.now);
      EXPECT_TRUE(chooser.run_pending());
      return chooser.poll(r.core, r.now);
    };
    select();
    select();  // two selections of the small loops: the median holds
    r.record = big;
    const std::uint64_t refits_before = chooser.count(ModelChooser::refits);
    const ModelDecision first = select();
    if (factor == 0.0) {
      EXPECT_EQ(first.kind, ModelDecision::Kind::refit) << chooser.last_reason();
      continue;
    }
    EXPECT_EQ(first.kind, ModelDecision::Kind::none);
    EXPECT_NE(chooser.last_reason().find("change of regime"), std::string::npos) << chooser.last_reason();
    EXPECT_EQ(select().kind, ModelDecision::Kind::none) << chooser.last_reason();
    EXPECT_EQ(chooser.count(ModelChooser::unsettled), 2u);
    EXPECT_EQ(chooser.count(ModelChooser::refits), refits_before);
    EXPECT_EQ(select().kind, ModelDecision::Kind::refit) << chooser.last_reason();  // the regime lasted
    EXPECT_EQ(chooser.count(ModelChooser::unsettled), 2u);
  }
}

TEST(ReidentModelChooser, ConfigKeys) {
  const auto read = [](const std::string& yaml) { return read_reident_options(Config::from_string(yaml)); };
  EXPECT_FALSE(read("reidentifier: {}").models.enabled);
  const ReidentOptions o = read("reidentifier: {models: \"mem,pi\", model_margin: 0.2, pin_model: pi}");
  EXPECT_TRUE(o.models.enabled);
  EXPECT_EQ(o.models.selector.selection.candidates, (std::vector<ModelKind>{ModelKind::mem, ModelKind::pi}));
  EXPECT_DOUBLE_EQ(o.models.selector.margin, 0.2);
  EXPECT_EQ(o.models.pinned, ModelKind::pi);
  EXPECT_DOUBLE_EQ(o.models.regime_factor, 3.0);
  EXPECT_DOUBLE_EQ(read("reidentifier: {model_regime_factor: 0}").models.regime_factor, 0.0);
  EXPECT_EQ(read("reidentifier: {models: auto}").models.selector.selection.candidates.size(), 4u);
  for (const char* bad : {"reidentifier: {models: banning}", "reidentifier: {models: \"mem,mem\"}",
                          "reidentifier: {model_margin: 0.95}", "reidentifier: {pin_model: preisach}",
                          "reidentifier: {model_decimation: 0}", "reidentifier: {model_period_s: 0}",
                          "reidentifier: {model_regime_factor: 0.5}", "reidentifier: {model_regime_factor: -1}"}) {
    EXPECT_THROW(read(bad), ConfigError) << bad;
  }
}

}  // namespace
}  // namespace hystloop
