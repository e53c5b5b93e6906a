// ReidentCore with a fake clock and the worker stepped by hand: scheduling (one job in flight,
// the period, a full window of new data), adoption and versions, garbage refused and counted,
// skipped and missing samples, health, and an allocation-free per-sample path.
#include "reidentifier/reident_core.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "hystloop/sensor_sample_t.hpp"
#include "services/reident_test_data.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

using testdata::gain_scaled;
using Kind = RefitDecision::Kind;

constexpr std::int64_t kSecond = 1'000'000;  // us
// The flag bits as plain ints (LCM's constants are distinct unnamed enums).
constexpr std::int32_t kSaturated = sensor_sample_t::SATURATED;
constexpr std::int32_t kSafeState = sensor_sample_t::SAFE_STATE;
constexpr std::int32_t kSimulated = sensor_sample_t::SIMULATED;
constexpr std::int32_t kLateCommand = sensor_sample_t::LATE_COMMAND;
constexpr std::int32_t kSensorFault = sensor_sample_t::SENSOR_FAULT;

struct Rig {
  MemParams initial = testdata::piezo_truth();
  MemParams truth = gain_scaled(initial, 1.1);
  ReidentCore core{testdata::small_reident_options(initial), "reident@test", /*start_thread=*/false};
  std::int64_t seq = 0;
  std::int64_t now = 10 * kSecond;  // fake clock [us]

  // One continuous 10 Hz record of the truth (the MEM state carries over between slices).
  testdata::SineRecord truth_record = testdata::sine_record(truth, 1, 6.0);
  std::size_t position = 0;

  // Streams the next `seconds` of the truth's record.
  void advance(double seconds = 1.0) {
    const auto n = static_cast<std::size_t>(std::llround(seconds * 1e4));
    for (std::size_t k = 0; k < n; ++k, ++position) {
      core.on_sample(seq++, truth_record.u.at(position), truth_record.y.at(position), 0, now);
      now += 100;
    }
  }
  // Streams `rec` at 10 kHz of fake time.
  void stream(const testdata::SineRecord& rec, std::int32_t flags = 0) {
    for (std::size_t k = 0; k < rec.u.size(); ++k) {
      core.on_sample(seq++, rec.u[k], rec.y[k], flags, now);
      now += 100;
    }
  }
  // poll; if that started a job, run it and poll again for the decision.
  RefitDecision refit() {
    RefitDecision d = core.poll(now);
    if (core.worker().run_pending()) d = core.poll(now);
    return d;
  }
};

TEST(ReidentCore, AdoptsABetterSetWithTheNextVersion) {
  Rig rig;
  rig.advance();
  const RefitDecision d = rig.refit();
  ASSERT_EQ(d.kind, Kind::accepted) << to_string(d.status);
  EXPECT_EQ(d.version, 2);
  EXPECT_TRUE(d.fitted);
  EXPECT_LT(testdata::rel_err(d.candidate.c1, rig.truth.c1), 0.01);
  EXPECT_GT(d.holdout_rms_candidate_m, 0.0);
  EXPECT_LT(d.holdout_rms_candidate_m, 0.5 * d.holdout_rms_in_use_m);
  EXPECT_EQ(d.window_samples, 5000u);
  EXPECT_EQ(rig.core.in_use().version(), 2);
  EXPECT_DOUBLE_EQ(rig.core.in_use().params().c1, d.candidate.c1);
  const ReidentCounters& c = rig.core.counters();
  EXPECT_EQ(c.get(ReidentCounter::refits_attempted), 1u);
  EXPECT_EQ(c.get(ReidentCounter::refits_accepted), 1u);
  EXPECT_EQ(c.rejected_total(), 0u);
  EXPECT_EQ(rig.core.refit_time().count(), 1u);

  // The plant has not changed since: the next refit is valid but not better.
  rig.now += kSecond;
  rig.advance();
  const RefitDecision again = rig.refit();
  EXPECT_EQ(again.kind, Kind::refused);
  EXPECT_EQ(again.status, FitStatus::no_improvement);
  EXPECT_EQ(rig.core.counters().rejected(FitStatus::no_improvement), 1u);
  EXPECT_EQ(rig.core.in_use().version(), 2);
}

TEST(ReidentCore, SchedulesOneRefitPerPeriodOnceAFullWindowOfNewDataIsThere) {
  Rig rig;
  rig.advance(0.4);  // less than a window
  EXPECT_EQ(rig.core.poll(rig.now).kind, Kind::none);
  EXPECT_TRUE(rig.core.worker().idle());  // nothing started: the window is not full
  rig.advance(0.2);
  rig.core.poll(rig.now);
  EXPECT_FALSE(rig.core.worker().idle());  // started
  // In flight: later polls start nothing else and decide nothing.
  rig.now += 5 * kSecond;
  EXPECT_EQ(rig.core.poll(rig.now).kind, Kind::none);
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::refits_attempted), 1u);
  ASSERT_TRUE(rig.core.worker().run_pending());
  EXPECT_NE(rig.core.poll(rig.now).kind, Kind::none);  // collected; the period since the start has passed ...
  EXPECT_TRUE(rig.core.worker().idle());               // ... but no new sample arrived: no refit
  rig.advance(0.01);
  rig.core.poll(rig.now);
  EXPECT_FALSE(rig.core.worker().idle());
  ASSERT_TRUE(rig.core.worker().run_pending());
  rig.core.poll(rig.now);
  // Period: a refit started at t starts the next at t + refit_period_s, not before.
  rig.advance(0.1);
  rig.core.poll(rig.now);
  EXPECT_TRUE(rig.core.worker().idle());
  rig.now += kSecond;
  rig.core.poll(rig.now);
  EXPECT_FALSE(rig.core.worker().idle());
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::refits_attempted), 3u);
}

TEST(ReidentCore, AnOutcomeJudgedAgainstAReplacedSetIsNotAdopted) {
  Rig rig;
  rig.advance();
  rig.core.poll(rig.now);  // job judged against version 1
  // Meanwhile hystloop-identify publishes version 4.
  EXPECT_EQ(rig.core.on_params(rig.initial, 4, true, "identify@lab"), ParamsOffer::adopted);
  ASSERT_TRUE(rig.core.worker().run_pending());
  const RefitDecision d = rig.core.poll(rig.now);
  EXPECT_EQ(d.kind, Kind::superseded);
  EXPECT_EQ(rig.core.in_use().version(), 4);
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::refits_superseded), 1u);
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::params_adopted), 1u);
  // The next refit is judged against version 4 and, accepted, published as 5.
  rig.now += kSecond;
  rig.advance(0.1);
  const RefitDecision next = rig.refit();
  ASSERT_EQ(next.kind, Kind::accepted) << to_string(next.status);
  EXPECT_EQ(next.version, 5);
  EXPECT_EQ(rig.core.on_params(next.candidate, 5, true, "reident@test"), ParamsOffer::echo);
}

TEST(ReidentCore, GarbageIsRefusedCountedAndNeverAdopted) {
  Rig rig;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // NaN samples refused on the wire poison every window that holds them.
  rig.advance();
  rig.core.on_refused_sample(rig.now);
  EXPECT_EQ(rig.refit().status, FitStatus::poisoned_window);
  // A NaN that reached the core some other way does the same.
  rig.core.on_sample(rig.seq++, 1.0, nan, 0, rig.now);
  rig.now += kSecond;
  EXPECT_EQ(rig.refit().status, FitStatus::poisoned_window);
  EXPECT_FALSE(rig.core.poisoned());
  // Stuck y (sensor dropout) while u moves.
  testdata::SineRecord stuck = testdata::sine_record(rig.truth, 10, 0.3);
  for (double& y : stuck.y) y = 1e-7;
  rig.stream(stuck);
  rig.now += kSecond;
  EXPECT_EQ(rig.refit().status, FitStatus::poisoned_window);
  EXPECT_TRUE(rig.core.poisoned());  // three windows in a row
  // Constant u (fills a clean window).
  testdata::SineRecord flat = testdata::sine_record(rig.truth, 11, 0.6);
  for (std::size_t k = 0; k < flat.u.size(); ++k) {
    flat.u[k] = 12.0;
    flat.y[k] = 1e-9 * std::sin(0.01 * static_cast<double>(k));
  }
  rig.stream(flat);
  rig.now += kSecond;
  EXPECT_EQ(rig.refit().status, FitStatus::constant_input);
  EXPECT_FALSE(rig.core.poisoned());

  const ReidentCounters& c = rig.core.counters();
  EXPECT_EQ(c.rejected(FitStatus::poisoned_window), 3u);
  EXPECT_EQ(c.rejected(FitStatus::constant_input), 1u);
  EXPECT_EQ(c.get(ReidentCounter::refits_accepted), 0u);
  EXPECT_EQ(c.get(ReidentCounter::non_finite), 2u);
  EXPECT_EQ(c.get(ReidentCounter::dropouts), 1u);
  EXPECT_EQ(rig.core.in_use().version(), 1);
  EXPECT_DOUBLE_EQ(rig.core.in_use().params().c1, rig.initial.c1);
}

TEST(ReidentCore, SkipsFlaggedSamplesAndCountsGapsAndRestarts) {
  Rig rig;
  rig.core.on_sample(0, 1.0, 1e-9, 0, rig.now);
  rig.core.on_sample(1, 1.0, 1e-9, kSafeState | kSimulated, rig.now);
  rig.core.on_sample(2, 1.0, 1e-9, kSensorFault, rig.now);
  rig.core.on_sample(3, 1.0, 1e-9, kSaturated | kLateCommand, rig.now);
  rig.core.on_sample(10, 1.0, 1e-9, 0, rig.now);  // 6 missing
  rig.core.on_sample(12, 1.0, 1e-9, 0, rig.now);  // 1 missing
  rig.core.on_refused_sample(rig.now);            // 13 (NaN, refused on the wire) ...
  rig.core.on_sample(14, 1.0, 1e-9, 0, rig.now);  // ... is no gap
  rig.core.on_refused_sample(rig.now);            // 15
  rig.core.on_sample(17, 1.0, 1e-9, 0, rig.now);  // 16 missing
  rig.core.on_sample(0, 1.0, 1e-9, 0, rig.now);   // the bridge restarted
  const ReidentCounters& c = rig.core.counters();
  EXPECT_EQ(c.get(ReidentCounter::samples_fed), 9u);  // incl. the two poison markers
  EXPECT_EQ(c.get(ReidentCounter::non_finite), 2u);
  EXPECT_EQ(c.get(ReidentCounter::skipped_safe_state), 1u);
  EXPECT_EQ(c.get(ReidentCounter::skipped_sensor_fault), 1u);
  EXPECT_EQ(c.get(ReidentCounter::seq_gaps), 3u);
  EXPECT_EQ(c.get(ReidentCounter::samples_missed), 8u);
  EXPECT_EQ(c.get(ReidentCounter::seq_restarts), 1u);
  rig.core.reset_counters();
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::samples_fed), 0u);
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::seq_gaps), 0u);
  rig.core.on_sample(1, 1.0, 2e-9, 0, rig.now);
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::samples_fed), 1u);
}

TEST(ReidentCore, StaleWhenNoSampleForLongerThanConfigured) {
  Rig rig;
  EXPECT_TRUE(rig.core.stale(rig.now));  // none yet
  EXPECT_FALSE(rig.core.seen_samples());
  rig.core.on_sample(0, 0.0, 0.0, 0, rig.now);
  EXPECT_FALSE(rig.core.stale(rig.now + kSecond));
  EXPECT_TRUE(rig.core.stale(rig.now + kSecond + 1));
  EXPECT_DOUBLE_EQ(rig.core.seconds_since_sample(rig.now + 2 * kSecond), 2.0);
}

TEST(ReidentCore, ThePerSamplePathAllocatesNothing) {
  Rig rig;
  const auto rec = testdata::sine_record(rig.truth, 12, 0.6);
  rig.stream(rec);
  rig.core.poll(rig.now);  // a job in flight: snapshotted
  testing::AllocationCounter counter;
  for (std::size_t k = 0; k < rec.u.size(); ++k) {
    rig.core.on_sample(rig.seq++, rec.u[k], rec.y[k], k % 7 == 0 ? kSafeState : 0, rig.now);
    if (k % 1000 == 0) rig.core.on_refused_sample(rig.now);
  }
  rig.core.poll(rig.now);  // in flight: nothing to do
  EXPECT_EQ(counter.allocations(), 0u);
}

TEST(ReidentCore, SnapshotAndCollectAllocateNothingOnTheOwnerThread) {
  Rig rig;
  rig.advance();
  rig.refit();  // warm-up: the result's strings got their capacity
  rig.now += kSecond;
  rig.advance(0.1);
  testing::AllocationCounter counter;
  rig.core.poll(rig.now);  // snapshot + submit
  const std::size_t at_submit = counter.allocations();
  rig.core.worker().run_pending();
  testing::AllocationCounter counter2;
  const RefitDecision d = rig.core.poll(rig.now);  // collect + decide
  EXPECT_NE(d.kind, Kind::none);
  EXPECT_EQ(at_submit, 0u);
  EXPECT_EQ(counter2.allocations(), 0u);
}

}  // namespace
}  // namespace hystloop
