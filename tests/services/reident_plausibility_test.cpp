// The re-identifier's plausibility checks (models/gain_plausibility.hpp against linear.gain over
// the actuator's range, reidentifier.plausible_gain_factor): a consistent plant 1000x too large (a
// units error) is fitted but neither published on HX_PARAMS nor on HX_MODEL, counted; the probe's
// HX_PARAMS sets (c2 = 1e300, c1 = 2.9e-322) are not adopted, counted, and their versions still
// seen; the configuration's own set and the keys are checked at start.
#include <gtest/gtest.h>

#include <string>

#include "core/config.hpp"
#include "reident/model_chooser.hpp"
#include "reident/reident_core.hpp"
#include "reidentifier/reident_options.hpp"
#include "services/reident_test_data.hpp"

namespace hystloop {
namespace {

using Kind = RefitDecision::Kind;
constexpr std::int64_t kSecond = 1'000'000;
constexpr std::int64_t kOther = 0x0dd0'0001;  // another publisher on HX_PARAMS

struct Rig {
  MemParams initial = testdata::piezo_truth();
  ReidentOptions options = testdata::small_reident_options(initial);
  ReidentCore core{options, "reident@test", /*start_thread=*/false};
  std::int64_t seq = 0;
  std::int64_t now = 10 * kSecond;
  sensor_block_t block = testdata::reserved_sensor_block();

  void stream(const testdata::SineRecord& rec, double seconds) {
    const auto n = static_cast<std::size_t>(std::llround(seconds * 1e4));
    for (std::size_t k = 0; k < n; k += 10) {
      testdata::fill_sensor_block(block, seq, now, rec.u, rec.y, k % (rec.u.size() - 10), 10);
      core.on_sensor_block(block, now);
      seq += 10;
      now += 1000;
    }
  }
  RefitDecision refit() {
    RefitDecision d = core.poll(now);
    if (core.worker().run_pending()) d = core.poll(now);
    return d;
  }
};

ModelParamSet mem_set(const MemParams& p) {
  ModelParamSet s;
  s.mem = p;
  return s;
}

TEST(ReidentPlausibility, APlant1000xTooLargeIsFittedButNotPublished) {
  Rig r;
  // Consistent, noise 1 nm: the fit explains it (the residual gate passes), its gain is the fault.
  const testdata::SineRecord mm = testdata::sine_record(testdata::gain_scaled(r.initial, 1e3), 5, 1.0);
  r.stream(mm, 1.0);
  const RefitDecision d = r.refit();
  ASSERT_TRUE(d.fitted);
  EXPECT_EQ(d.kind, Kind::refused);
  EXPECT_EQ(d.status, FitStatus::out_of_range);
  EXPECT_GT(d.candidate.c1, 100.0 * r.initial.c1);  // what it would have published
  const ReidentCounters& c = r.core.counters();
  EXPECT_EQ(c.get(ReidentCounter::refits_implausible), 1u);
  EXPECT_EQ(c.rejected(FitStatus::out_of_range), 1u);
  EXPECT_EQ(c.get(ReidentCounter::refits_accepted), 0u);
  EXPECT_EQ(r.core.in_use().version(), ParamsInUse::kInitialVersion);
  EXPECT_EQ(r.core.in_use().params().c1, r.initial.c1);

  // The same plant at its true scale, 10 % stiffer, is adopted as before.
  Rig fine;
  fine.stream(testdata::sine_record(testdata::gain_scaled(fine.initial, 1.1), 5, 1.0), 1.0);
  EXPECT_EQ(fine.refit().kind, Kind::accepted);
  EXPECT_EQ(fine.core.counters().get(ReidentCounter::refits_implausible), 0u);
}

TEST(ReidentPlausibility, TheModelChoiceDoesNotPublishAnImplausibleModel) {
  Rig r;
  ModelChoiceOptions o;
  o.enabled = true;
  o.period_s = 1.0;
  o.pinned = ModelKind::linear;  // switched to at the next selection, whatever it scores
  o.selector.decimation = 5;
  ModelChooser chooser(o, mem_set(r.initial), r.core.estimator().make_window(), false);
  r.stream(testdata::sine_record(testdata::gain_scaled(r.initial, 1e3), 3, 1.0), 0.6);
  chooser.poll(r.core, r.now);
  ASSERT_TRUE(chooser.run_pending());
  const ModelDecision d = chooser.poll(r.core, r.now);
  EXPECT_EQ(d.kind, ModelDecision::Kind::none) << chooser.last_reason();
  EXPECT_EQ(chooser.count(ModelChooser::implausible), 1u);
  EXPECT_NE(chooser.last_reason().find("linear.gain"), std::string::npos) << chooser.last_reason();
  EXPECT_EQ(chooser.in_use().kind, ModelKind::mem);
  EXPECT_TRUE(r.core.mem_refits());
  EXPECT_STREQ(ModelChooser::counter_name(ModelChooser::implausible), "model_implausible");
}

TEST(ReidentPlausibility, TheProbesParamsAreNotAdoptedButTheirVersionsAreSeen) {
  Rig r;
  const MemParams p = r.initial;
  EXPECT_EQ(r.core.on_params({p.c1, 1e300, p.c3}, 7, kOther, true, "probe"), ParamsOffer::invalid);
  EXPECT_NE(r.core.implausible_reason().find("mem.c2"), std::string::npos) << r.core.implausible_reason();
  EXPECT_EQ(r.core.on_params({2.9e-322, p.c2, p.c3}, 8, kOther, true, "probe"), ParamsOffer::invalid);
  EXPECT_NE(r.core.implausible_reason().find("subnormal"), std::string::npos) << r.core.implausible_reason();
  EXPECT_EQ(r.core.on_params({1e3 * p.c1, 1e3 * p.c2, p.c3}, 9, kOther, true, "probe"), ParamsOffer::invalid);
  const ReidentCounters& c = r.core.counters();
  EXPECT_EQ(c.get(ReidentCounter::params_implausible), 3u);
  EXPECT_EQ(c.get(ReidentCounter::params_invalid), 0u);
  EXPECT_EQ(c.get(ReidentCounter::params_adopted), 0u);
  EXPECT_EQ(r.core.in_use().version(), ParamsInUse::kInitialVersion);
  EXPECT_EQ(r.core.in_use().params().c2, p.c2);
  EXPECT_GE(r.core.in_use().highest_seen(), 9);  // our next set is numbered above them

  // A plausible set from the same publisher is adopted; one outside MEM's domain stays "invalid".
  EXPECT_EQ(r.core.on_params({1.1 * p.c1, 1.1 * p.c2, p.c3}, 10, kOther, true, "probe"), ParamsOffer::adopted);
  EXPECT_EQ(r.core.on_params({-1.0, p.c2, p.c3}, 11, kOther, true, "probe"), ParamsOffer::invalid);
  EXPECT_EQ(r.core.counters().get(ReidentCounter::params_invalid), 1u);
  EXPECT_EQ(r.core.counters().get(ReidentCounter::params_implausible), 3u);
}

TEST(ReidentPlausibility, TheBandComesFromTheSharedKeysAndTheInitialSetMustLieInIt) {
  const auto read = [](const std::string& yaml) { return read_reident_options(Config::from_string(yaml)); };
  const ReidentOptions d = read("reidentifier: {}");
  EXPECT_EQ(d.plausibility.nominal_gain_m_per_V, LinearParams{}.gain);
  EXPECT_EQ(d.plausibility.factor, 10.0);
  EXPECT_EQ(d.plausibility.u_max_V - d.plausibility.u_min_V, 500.0);
  const ReidentOptions o =
      read("linear: {gain: 5.0e-9}\nactuator: {u_min_V: 0, u_max_V: 150}\nreidentifier: {plausible_gain_factor: 20}");
  EXPECT_EQ(o.plausibility.nominal_gain_m_per_V, 5e-9);
  EXPECT_EQ(o.plausibility.u_max_V - o.plausibility.u_min_V, 150.0);
  EXPECT_EQ(o.plausibility.factor, 20.0);
  const auto refusal = [&](const std::string& yaml) {
    try {
      read(yaml);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(refusal("mem: {c1: 4.0e-6, c2: 2.0e-9, c3: 0.8}").find("mem.c1"), std::string::npos);
  EXPECT_NE(refusal("reidentifier: {plausible_gain_factor: 1.5}").find("reidentifier.plausible_gain_factor"),
            std::string::npos);
  EXPECT_NE(refusal("linear: {gain: 0}").find("linear.gain"), std::string::npos);
  EXPECT_NE(refusal("actuator: {u_min_V: 10, u_max_V: 0}").find("actuator.u_max_V"), std::string::npos);
}

}  // namespace
}  // namespace hystloop
