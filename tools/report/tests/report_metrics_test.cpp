// report_metrics on hand-made RunData: the definitions the tool's figures rest on.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/errors.hpp"
#include "hystloop/command_block_t.hpp"
#include "model_overlay.hpp"
#include "models/mem.hpp"
#include "report_metrics.hpp"

using namespace hystloop;
using namespace hystloop::report;

namespace {

constexpr std::int64_t kT0 = 1'000'000'000;

SampleRecord tick(std::int64_t t, std::int64_t seq, double y_ref, double y, std::int32_t flags = 0) {
  return {t, seq, 0.0, y_ref, y, flags};
}

// ticks at tick_us apart, reference 1 µm, y off by 0, 1 or 2 nm; every command at version 0.
RunData ramp_run(std::int64_t ticks, std::int64_t tick_us) {
  RunData run;
  for (std::int64_t k = 0; k < ticks; ++k) {
    run.samples.push_back(tick(kT0 + k * tick_us, k, 1e-6, 1e-6 + 1e-9 * static_cast<double>(k % 3)));
    run.command_versions.add(k, 0);
  }
  return run;
}

StatusRecord status(std::int64_t t, const std::string& process, std::vector<std::pair<std::string, std::int64_t>> c,
                    std::int64_t start_utime = 0) {
  StatusRecord s{t, process, 0, std::move(c)};
  s.utime = t;
  s.start_utime = start_utime;
  return s;
}

}  // namespace

TEST(NearestRank, MatchesTheDefinition) {
  EXPECT_FALSE(nearest_rank({}, 0.5));
  const std::vector<double> v{1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  EXPECT_EQ(*nearest_rank(v, 0.0), 1);
  EXPECT_EQ(*nearest_rank(v, 0.5), 5);   // ceil(5) = 5th
  EXPECT_EQ(*nearest_rank(v, 0.51), 6);  // ceil(5.1) = 6th
  EXPECT_EQ(*nearest_rank(v, 0.99), 10);
  EXPECT_EQ(*nearest_rank(v, 1.0), 10);
}

TEST(ReportOptions, RefusesBadRangesNamingTheOption) {
  ReportOptions o;
  o.skip_initial_s = -1;
  try {
    o.validate();
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "--skip-initial");
  }
  o = {};
  o.from_s = 4;
  o.to_s = 3;
  EXPECT_THROW(o.validate(), ParameterError);
  o.from_s = std::nan("");
  EXPECT_THROW(o.validate(), ParameterError);
  o = {};
  EXPECT_TRUE(std::isinf(o.lower_s()));
  o.skip_initial_s = 2;
  EXPECT_EQ(o.lower_s(), 2.0);
  o.from_s = 1;
  EXPECT_EQ(o.lower_s(), 3.0);
}

TEST(ComputeMetrics, RandomErrorsGiveTheirRms) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 30e-9);
  RunData run;
  double sum = 0;
  for (std::int64_t k = 0; k < 5000; ++k) {
    const double e = noise(rng);
    sum += e * e;
    run.samples.push_back(tick(kT0 + k * 100, k, 2e-6, 2e-6 - e));
    run.command_versions.add(k, 3);
  }
  for (std::int64_t b = 0; b < 500; ++b)
    run.command_blocks.push_back({kT0 + b * 1000, b * 10 + 305, b * 10 + 4 - b % 7});
  const auto m = compute_metrics(run, {});
  EXPECT_NEAR(*m.rms_error_m, std::sqrt(sum / 5000.0), 1e-18);
  EXPECT_NEAR(*m.rms_error_m, 30e-9, 2e-9);
  ASSERT_EQ(m.per_second.size(), 1u);
  EXPECT_EQ(m.per_second[0].params_version, 3);
  EXPECT_EQ(m.run_ahead_ticks.size(), 500u);
  EXPECT_EQ(*m.run_ahead_min_ticks, 301.0);  // b % 7 == 0
  EXPECT_EQ(*m.run_ahead_max_ticks, 307.0);
  EXPECT_EQ(*m.run_ahead_p50_ticks, 304.0);  // 7 values nearly equally often
  EXPECT_EQ(*m.late_command_fraction, 0.0);
}

TEST(ComputeMetrics, EmptySecondsAreListedAndCarryTheVersion) {
  RunData run;
  run.samples.push_back(tick(kT0, 0, 1e-6, 1e-6));
  run.command_versions.add(0, 5);
  run.samples.push_back(tick(kT0 + 3'500'000, 1, std::nan(""), 1e-6));  // seconds 1 and 2 have nothing
  const auto m = compute_metrics(run, {});
  ASSERT_EQ(m.per_second.size(), 4u);
  EXPECT_EQ(m.per_second[2].tracking_samples, 0u);
  EXPECT_FALSE(m.per_second[2].rms_error_m);
  EXPECT_EQ(m.per_second[3].params_version, 5);
  EXPECT_EQ(m.seq_gaps, 0);
  EXPECT_EQ(m.tracking_samples, 1u);  // tick 1 has no reference: not tracking
}

TEST(ComputeMetrics, TheErrorIsTheReferenceMinusTheMeasuredPositionOfEachTick) {
  RunData run = ramp_run(10, 100);
  run.samples[2].y_ref_m = std::nan("");  // tick 2 has no reference
  run.samples[4].y_m = 1e-6 + 7e-9;
  const auto m = compute_metrics(run, {});
  EXPECT_EQ(m.tracking_samples, 9u);
  EXPECT_NEAR(*m.max_abs_error_m, 7e-9, 1e-18);
  const auto points = track_points(run, {});
  ASSERT_EQ(points.size(), 10u);
  EXPECT_TRUE(std::isnan(points[2].y_ref_m));
  EXPECT_EQ(points[4].y_m, 1e-6 + 7e-9);
}

TEST(CommandVersions, FirstLoggedCommandForATickWinsAndRunsCoalesce) {
  CommandVersions v;
  for (std::int64_t k = 10; k < 20; ++k) v.add(k, 1);
  for (std::int64_t k = 15; k < 25; ++k) v.add(k, 2);  // 15..19 re-sent: ignored
  v.add(30, 2);                                        // after a gap
  EXPECT_EQ(v.runs().size(), 3u);
  EXPECT_FALSE(v.at(9));
  EXPECT_EQ(*v.at(10), 1);
  EXPECT_EQ(*v.at(19), 1);
  EXPECT_EQ(*v.at(20), 2);
  EXPECT_EQ(*v.at(24), 2);
  EXPECT_FALSE(v.at(25));
  EXPECT_EQ(*v.at(30), 2);
  EXPECT_FALSE(v.at(31));
}

TEST(ComputeMetrics, NothingArmedGivesNoLateFraction) {
  RunData run = ramp_run(10, 100);
  for (auto& s : run.samples) s.flags = 2 | 16;  // SAFE_STATE | LATE_COMMAND
  run.sensor_blocks.push_back({kT0 + 900, 1e-4, 0, false});
  const auto m = compute_metrics(run, {});
  EXPECT_EQ(m.armed_samples, 0u);
  EXPECT_FALSE(m.late_command_fraction);
  EXPECT_EQ(m.sensor_blocks, 1u);
  EXPECT_FALSE(m.buffer_min_depth_ticks);  // only armed blocks count
  EXPECT_EQ(*m.watchdog_trips, 0);         // never armed: nothing tripped
}

TEST(ComputeMetrics, LateFractionAndBufferDepthCountArmedTicksAndBlocksOnly) {
  RunData run = ramp_run(100, 100);
  for (std::int64_t k = 0; k < 100; ++k) {
    auto& s = run.samples[static_cast<std::size_t>(k)];
    if (k < 20) s.flags |= 2;        // SAFE_STATE: not counted, late or not
    if (k % 10 == 3) s.flags |= 16;  // LATE_COMMAND: ticks 3, 13 safe; 23 .. 93 armed
  }
  for (std::int64_t b = 0; b < 10; ++b) {
    run.sensor_blocks.push_back({kT0 + b * 1000 + 900, 1e-4, static_cast<std::int32_t>(b == 1 ? 0 : 40 - b), b >= 2});
  }
  const auto m = compute_metrics(run, {});
  EXPECT_EQ(m.armed_samples, 80u);
  EXPECT_EQ(m.late_samples, 8u);
  EXPECT_DOUBLE_EQ(*m.late_command_fraction, 0.1);
  EXPECT_EQ(m.sensor_blocks, 10u);
  EXPECT_EQ(m.armed_blocks, 8u);
  EXPECT_EQ(*m.buffer_min_depth_ticks, 31);  // block 9; block 1's 0 was in the safe state
  EXPECT_EQ(*m.tick_period_s, 1e-4);
}

// SATURATED = 1 (range), SLEW_LIMITED = 8; a tick flagged with both is one clamped tick.
TEST(ComputeMetrics, ClampedTicksFromTheirFlagsInTotalAndPerSecond) {
  RunData run = ramp_run(30, 100'000);                             // 10 ticks a second for 3 s
  const std::int32_t flags[30] = {1, 8, 9, 0, 0, 0, 0, 0,  0, 0,   // second 0: 3 clamped (2 range, 2 slew)
                                  0, 0, 0, 0, 0, 0, 0, 0,  0, 0,   // second 1: none
                                  8, 8, 8, 8, 9, 1, 2, 16, 0, 0};  // second 2: 6 (2 range, 5 slew)
  for (std::size_t k = 0; k < 30; ++k) run.samples[k].flags = flags[k];
  const auto m = compute_metrics(run, {});
  EXPECT_EQ(m.clamped_range_samples, 4u);
  EXPECT_EQ(m.clamped_slew_samples, 7u);
  EXPECT_EQ(m.clamped_samples, 9u);
  ASSERT_EQ(m.per_second.size(), 3u);
  EXPECT_EQ(m.per_second[0].clamped_samples, 3u);
  EXPECT_EQ(m.per_second[1].clamped_samples, 0u);
  EXPECT_EQ(m.per_second[2].clamped_samples, 6u);
  ReportOptions from_one;  // the range selects the ticks counted
  from_one.from_s = 1.0;
  EXPECT_EQ(compute_metrics(run, from_one).clamped_samples, 6u);
}

TEST(ComputeMetrics, WatchdogTripsFromTheBridgeCounterElseFromTheTicks) {
  RunData run = ramp_run(100, 10'000);  // 10 ms apart
  auto safe = [&](std::int64_t from, std::int64_t to) {
    for (std::int64_t k = from; k < to; ++k) run.samples[static_cast<std::size_t>(k)].flags |= 2;
  };
  safe(0, 10);    // the start: not a trip
  safe(30, 40);   // a trip
  safe(60, 70);   // a DISARM: not a trip
  safe(90, 100);  // a trip
  run.safe_requests.push_back({kT0 + 595'000, "bridge"});
  run.safe_requests.push_back({kT0 + 295'000, "compensator"});  // not for the bridge
  auto m = compute_metrics(run, {});
  EXPECT_EQ(*m.watchdog_trips, 2);
  EXPECT_NE(m.watchdog_trips_source.find("transitions"), std::string::npos);
  run.statuses.push_back(status(kT0, "bridge", {{"watchdog_trips", 5}}));
  m = compute_metrics(run, {});
  EXPECT_EQ(*m.watchdog_trips, 5);
  EXPECT_NE(m.watchdog_trips_source.find("watchdog_trips"), std::string::npos);
}

TEST(ComputeMetrics, CpuFractionPerProcessAddsItsSegments) {
  RunData run = ramp_run(10, 100);
  // bridge: 0.25 of a core for 2 s, then restarted (counters from 0) and 0.5 for 1 s.
  run.statuses.push_back(status(kT0, "bridge", {{"cpu_user_us", 1'000'000}, {"cpu_system_us", 0}}, 1));
  run.statuses.push_back(
      status(kT0 + 2'000'000, "bridge", {{"cpu_user_us", 1'400'000}, {"cpu_system_us", 100'000}}, 1));
  run.statuses.push_back(status(kT0 + 3'000'000, "bridge", {{"cpu_user_us", 10}, {"cpu_system_us", 0}}, 2));
  run.statuses.push_back(status(kT0 + 4'000'000, "bridge", {{"cpu_user_us", 250'010}, {"cpu_system_us", 250'000}}, 2));
  run.statuses.push_back(status(kT0, "logger", {{"cpu_user_us", 0}}));  // no system time: no figure
  run.statuses.push_back(status(kT0 + 1'000'000, "logger", {{"cpu_user_us", 5}}));
  run.statuses.push_back(status(kT0, "compensator", {{"cpu_user_us", 7}, {"cpu_system_us", 1}}));  // one report
  const auto m = compute_metrics(run, {});
  ASSERT_EQ(m.cpu_fraction.size(), 3u);
  EXPECT_NEAR(*m.cpu_fraction.at("bridge"), (500'000.0 + 500'000.0) / 3'000'000.0, 1e-12);
  EXPECT_FALSE(m.cpu_fraction.at("logger"));
  EXPECT_FALSE(m.cpu_fraction.at("compensator"));
}

TEST(ComputeMetrics, MessageRatesCountTheEventsOfTheSampledSpan) {
  RunData run = ramp_run(10'001, 100);  // 1 s of ticks
  for (std::int64_t i = 0; i <= 1000; ++i) run.event_times["HX_SENSOR"].push_back(kT0 + i * 1000);
  run.event_times["HX_STATUS"] = {kT0 - 10, kT0 + 500'000, kT0 + 1'000'000, kT0 + 1'000'001};  // 2 inside
  const auto m = compute_metrics(run, {});
  EXPECT_DOUBLE_EQ(m.duration_s, 1.0);
  EXPECT_DOUBLE_EQ(*m.messages_per_s.at("HX_SENSOR"), 1001.0);
  EXPECT_DOUBLE_EQ(*m.messages_per_s.at("HX_STATUS"), 2.0);
  RunData empty;
  empty.event_times["HX_STATUS"] = {kT0};
  EXPECT_FALSE(compute_metrics(empty, {}).messages_per_s.at("HX_STATUS"));
}

TEST(ComputeMetrics, RejectedCommandsFallBackToTheStatusField) {
  RunData run = ramp_run(10, 100);
  auto m = compute_metrics(run, {});
  EXPECT_FALSE(m.commands_rejected);
  run.statuses.push_back({kT0, "bridge", 9, {{"ticks", 10}, {"control.rejected_out_of_range", 4}}, kT0, 0});
  m = compute_metrics(run, {});
  EXPECT_EQ(*m.commands_rejected, 9);  // no command reject counter: the 'rejected' field
  run.statuses.push_back({kT0 + 10, "bridge", 9, {{"cmd.rejected_non_finite", 2}, {"rejected_future", 1}}, kT0, 0});
  m = compute_metrics(run, {});
  EXPECT_EQ(*m.commands_rejected, 3);
  EXPECT_EQ(m.commands_rejected_counters.size(), 2u);
}

TEST(ComputeMetrics, LoggerGapsPreferTheExactCounterName) {
  RunData run = ramp_run(10, 100);
  run.samples.erase(run.samples.begin() + 4, run.samples.begin() + 6);  // seq 4, 5 missing
  auto m = compute_metrics(run, {});
  EXPECT_EQ(*m.logger_gaps, 1);
  EXPECT_EQ(m.missing_samples, 2);
  run.statuses.push_back(status(kT0, "logger", {{"gap_samples", 40}, {"sensor_gaps", 3}}));
  m = compute_metrics(run, {});
  EXPECT_EQ(*m.logger_gaps, 3);
  run.statuses.push_back(status(kT0, "logger", {{"gaps", 6}, {"sensor_gaps", 3}}));
  m = compute_metrics(run, {});
  EXPECT_EQ(*m.logger_gaps, 6);
}

TEST(ComputeMetrics, ParamsBeforeTheRangeAreTheInitialSet) {
  RunData run = ramp_run(50'000, 100);  // 5 s
  run.params.push_back({kT0 - 1, 1, 1e-7, 0, 1, 0, true});
  run.params.push_back({kT0 + 1'000'000, 2, 2e-7, 0, 1, 0, true});
  run.params.push_back({kT0 + 2'000'000, 3, 3e-7, 0, 1, 0, false});
  run.params.push_back({kT0 + 3'000'000, 4, 4e-7, 0, 1, 0, true});
  ReportOptions o;
  o.from_s = 1.5;
  o.to_s = 2.5;
  auto m = compute_metrics(run, o);
  EXPECT_EQ(m.params_initial->version, 2);
  EXPECT_EQ(m.params_final->version, 2);
  EXPECT_EQ(m.params_updates, 0u);
  ASSERT_EQ(m.params_history.size(), 1u);
  EXPECT_FALSE(m.params_history[0].valid);
  m = compute_metrics(run, {});
  EXPECT_EQ(m.params_initial->version, 1);
  EXPECT_EQ(m.params_final->version, 4);
  EXPECT_EQ(m.params_updates, 2u);
  EXPECT_EQ(m.samples, 50'000u);
  EXPECT_NEAR(m.duration_s, 4.9999, 1e-9);
}

TEST(CommandVersions, AModeChangeStartsARunAndEachTickKeepsItsMode) {
  CommandVersions v;
  for (std::int64_t k = 0; k < 10; ++k) v.add(k, 0, 5);   // an experiment
  for (std::int64_t k = 10; k < 20; ++k) v.add(k, 0, 1);  // linear, same version
  EXPECT_EQ(v.runs().size(), 2u);
  ASSERT_NE(v.run_at(9), nullptr);
  EXPECT_EQ(v.run_at(9)->mode, 5);
  EXPECT_EQ(v.run_at(10)->mode, 1);
  EXPECT_EQ(v.run_at(20), nullptr);
}

TEST(ComputeMetrics, ASwapIsDatedAtTheFirstTickCommandedWithTheNewVersion) {
  RunData run;
  for (std::int64_t k = 0; k < 3000; ++k) {
    run.samples.push_back(tick(kT0 + k * 1000, k, 1e-6, 1e-6));
    run.command_versions.add(k, k < 1234 ? 1 : (k < 2345 ? 2 : 5), 2);
  }
  const auto m = compute_metrics(run, {});
  ASSERT_EQ(m.swaps.size(), 2u);
  EXPECT_EQ(m.swaps[0].seq, 1234);
  EXPECT_DOUBLE_EQ(m.swaps[0].t_s, 1.234);  // not the start of its second
  EXPECT_EQ(m.swaps[0].from, 1);
  EXPECT_EQ(m.swaps[0].to, 2);
  EXPECT_EQ(m.swaps[1].seq, 2345);
  EXPECT_EQ(m.swaps[1].to, 5);
  const auto points = track_points(run, {});
  EXPECT_EQ(points[1233].params_version, 1);
  EXPECT_EQ(points[1234].params_version, 2);
  EXPECT_EQ(points[0].mode, 2);
}

TEST(MemModelY, IsTheSetInUseForTheSameUAndTheFirstIdentifiedBeforeAnySet) {
  const hystloop::MemParams stage = hystloop::MemParams::paper_like();
  ReportMetrics m;
  m.params_history.push_back({5.0, 7, stage.c1, stage.c2, stage.c3, 1e-9, true, "mem", 1e-9, false});
  m.params_history.push_back({6.0, 8, 2 * stage.c1, stage.c2, stage.c3, 1e-9, false, "mem", 1e-9, false});  // invalid
  std::vector<TrackPoint> ticks;
  hystloop::MemModel truth(stage);
  for (int k = 0; k < 10'000; ++k) {
    const double u = 200.0 * std::sin(2.0 * M_PI * k / 2000.0);
    TrackPoint p{k * 1e-3, u, truth.forward(u) + 1e-7, std::nan("")};  // the stage 0.1 µm off the model's origin
    if (k >= 5000) p.params_version = 7;
    ticks.push_back(p);
  }
  const auto y = mem_model_y(ticks, m);
  ASSERT_EQ(y.size(), ticks.size());
  for (std::size_t i = 0; i < y.size(); ++i) ASSERT_NEAR(y[i], ticks[i].y_m, 1e-15) << i;

  m.params_history[0].valid = false;  // no valid set: nothing to draw
  EXPECT_TRUE(mem_model_y(ticks, m).empty());
}

// An identification experiment is drawn with the set fitted from it (published after it), not
// the set it is to replace; and every branch starts at the measured y of its reversal, so a
// stage that creeps away from the model moves the model with it.
TEST(MemModelY, AnExperimentGetsTheSetFittedFromItAndEachBranchStartsAtTheMeasuredReversal) {
  const hystloop::MemParams stage = hystloop::MemParams::paper_like();
  hystloop::MemParams wrong = stage;
  wrong.c1 *= 3.0;
  ReportMetrics m;
  m.params_history.push_back({-1.0, 1, wrong.c1, wrong.c2, wrong.c3, 1e-9, true, "mem", 1e-9, false});
  m.params_history.push_back({15.0, 1, wrong.c1, wrong.c2, wrong.c3, 0.0, true, "mem", 0.0, false});  // by hand
  m.params_history.push_back({20.0, 2, stage.c1, stage.c2, stage.c3, 1e-9, true, "mem", 1e-9, false});
  std::vector<TrackPoint> ticks;
  hystloop::MemModel truth(stage);
  std::vector<std::size_t> reversal_ticks;
  double prev_du = 0.0, prev_u = 0.0;
  for (int k = 0; k < 10'000; ++k) {
    const double u = 200.0 * std::sin(2.0 * M_PI * k / 2000.0);
    const double creep_m = 2e-12 * k;  // 20 nm over the record
    TrackPoint p{k * 1e-3, u, truth.forward(u) + creep_m, std::nan("")};
    p.mode = command_block_t::MODE_EXPERIMENT;
    p.params_version = 1;  // the set in use while the experiment runs
    ticks.push_back(p);
    const double du = u - prev_u;
    if (k > 1 && du * prev_du < 0.0) reversal_ticks.push_back(static_cast<std::size_t>(k - 1));
    prev_du = du, prev_u = u;
  }
  const auto y = mem_model_y(ticks, m);
  ASSERT_EQ(y.size(), ticks.size());
  ASSERT_GE(reversal_ticks.size(), 8u);
  // With the set fitted from the experiment the model follows the stage to its creep within a
  // branch (at most the 2 pm/tick creep of one branch, 1000 ticks), not the wrong set's 3x slope.
  double worst = 0.0;
  for (std::size_t i = 0; i < y.size(); ++i) worst = std::max(worst, std::abs(y[i] - ticks[i].y_m));
  EXPECT_LT(worst, 2.5e-9);
}
