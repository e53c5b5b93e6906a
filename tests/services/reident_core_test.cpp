// ReidentCore with a fake clock and the worker stepped by hand: scheduling (one job in flight,
// the period, a full window of new data), adoption and versions, garbage refused and counted,
// skipped, refused and missing ticks, the version the compensator applies (HX_COMMAND ahead of
// the samples), health, and an allocation-free block path.
#include "reident/reident_core.hpp"

#include <gtest/gtest.h>

#include <array>
#include <limits>

#include "hystloop/sensor_block_t.hpp"
#include "services/reident_test_data.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

using testdata::gain_scaled;
using testdata::sample_tick;
using Kind = RefitDecision::Kind;

constexpr std::int64_t kSecond = 1'000'000;  // us
constexpr std::size_t kBlockTicks = 10;      // the bridge's default block
// The flag bits as plain ints (LCM's constants are distinct unnamed enums).
constexpr std::int32_t kSaturated = sensor_block_t::SATURATED;
constexpr std::int32_t kSafeState = sensor_block_t::SAFE_STATE;
constexpr std::int32_t kSimulated = sensor_block_t::SIMULATED;
constexpr std::int32_t kLateCommand = sensor_block_t::LATE_COMMAND;
constexpr std::int32_t kSensorFault = sensor_block_t::SENSOR_FAULT;

struct Rig {
  MemParams initial = testdata::piezo_truth();
  MemParams truth = gain_scaled(initial, 1.1);
  ReidentCore core{testdata::small_reident_options(initial), "reident@test", /*start_thread=*/false};
  std::int64_t seq = 0;
  std::int64_t now = 10 * kSecond;  // fake clock [us]
  sensor_block_t block = testdata::reserved_sensor_block();

  // One continuous 10 Hz record of the truth (the MEM state carries over between slices).
  testdata::SineRecord truth_record = testdata::sine_record(truth, 1, 6.0);
  std::size_t position = 0;

  // Sends u/y[from, from + n) as HX_SENSOR blocks of kBlockTicks, 10 kHz of fake time.
  void send(const std::vector<double>& u, const std::vector<double>& y, std::size_t from, std::size_t n,
            std::int32_t flags = 0) {
    for (std::size_t k = from; k < from + n; k += kBlockTicks) {
      const std::size_t ticks = std::min(kBlockTicks, from + n - k);
      testdata::fill_sensor_block(block, seq, now, u, y, k, ticks, flags);
      core.on_sensor_block(block, now);
      seq += static_cast<std::int64_t>(ticks);
      now += static_cast<std::int64_t>(ticks) * testdata::kTickPeriod_us;
    }
  }
  // Streams the next `seconds` of the truth's record.
  void advance(double seconds = 1.0) {
    const auto n = static_cast<std::size_t>(std::llround(seconds * 1e4));
    send(truth_record.u, truth_record.y, position, n);
    position += n;
  }
  // Streams `rec`.
  void stream(const testdata::SineRecord& rec, std::int32_t flags = 0) { send(rec.u, rec.y, 0, rec.u.size(), flags); }
  // One tick, seq given.
  void tick(std::int64_t s, std::int32_t flags = 0) {
    core.on_sample(SensorTick{.seq = s, .u_V = 1.0, .y_m = 1e-9, .flags = flags}, now);
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
  // The fit lands 2.7e-4 from the true c1 on this record (1 nm noise); 1e-3 leaves room for another
  // standard library's normal_distribution drawing other noise, and still fails a fit that is off.
  EXPECT_LT(testdata::rel_err(d.candidate.c1, rig.truth.c1), 1e-3);
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

TEST(ReidentCore, HeldItJudgesAndCountsABetterSetButAdoptsNothingUntilReleased) {
  Rig rig;
  rig.core.hold(true);
  rig.advance();
  const RefitDecision held = rig.refit();
  ASSERT_EQ(held.kind, Kind::held) << to_string(held.status);
  EXPECT_LT(testdata::rel_err(held.candidate.c1, rig.truth.c1), 1e-3);  // fitted (as above) and reported
  EXPECT_LT(held.holdout_rms_candidate_m, 0.5 * held.holdout_rms_in_use_m);
  EXPECT_EQ(rig.core.in_use().version(), 1);  // the set in use stays
  EXPECT_DOUBLE_EQ(rig.core.in_use().params().c1, rig.initial.c1);
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::refits_held), 1u);
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::refits_accepted), 0u);

  rig.core.hold(false);  // released: the next refit that beats the set in use is adopted
  rig.now += kSecond;
  rig.advance();
  const RefitDecision released = rig.refit();
  ASSERT_EQ(released.kind, Kind::accepted) << to_string(released.status);
  EXPECT_EQ(rig.core.in_use().version(), released.version);
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::refits_held), 1u);
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

// A new reference requested: a window that holds another line (a reference that moved) starts
// again, and the next refit waits for a full window of the new reference (a window holding the end
// of one line and the start of the next is fitted by a set that explains neither). A window of an
// experiment (no reference) is kept: the line after it is fitted on its loops.
TEST(ReidentCore, ANewReferenceStartsAWindowThatHoldsAnotherLineAgain) {
  Rig rig;
  rig.advance(0.6);  // an experiment: u and y, no reference (more than a window, 0.5 s here)
  EXPECT_FALSE(rig.core.on_new_reference());
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::window_restarts), 0u);
  rig.core.poll(rig.now);
  EXPECT_FALSE(rig.core.worker().idle());  // refitted on the experiment's window
  ASSERT_TRUE(rig.core.worker().run_pending());
  rig.core.poll(rig.now);
  // A line: the reference moves (here the record's own y).
  const auto line = [&](double seconds) {
    const auto n = static_cast<std::size_t>(std::llround(seconds * 1e4));
    for (std::size_t k = 0; k < n; ++k, ++rig.position) {
      rig.core.on_sample(SensorTick{.seq = rig.seq++,
                                    .u_V = rig.truth_record.u[rig.position],
                                    .u_ff_V = rig.truth_record.u[rig.position],
                                    .y_ref_m = rig.truth_record.y[rig.position],
                                    .y_m = rig.truth_record.y[rig.position]},
                         rig.now);
      rig.now += testdata::kTickPeriod_us;
    }
  };
  line(0.6);
  rig.now += 2 * kSecond;  // the refit period has passed
  EXPECT_TRUE(rig.core.on_new_reference());
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::window_restarts), 1u);
  rig.core.poll(rig.now);
  EXPECT_TRUE(rig.core.worker().idle());  // the window holds the line before only
  line(0.4);
  rig.core.poll(rig.now);
  EXPECT_TRUE(rig.core.worker().idle());  // 0.4 s of the new one
  // Someone else's worse set in use meanwhile: the next refit would be adopted.
  ASSERT_EQ(rig.core.on_params(rig.initial, 50, 42, true, "test"), ParamsOffer::adopted);
  line(0.2);
  rig.core.poll(rig.now);
  EXPECT_FALSE(rig.core.worker().idle());  // a full window of it
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::refits_attempted), 2u);
  // A refit of that window, finished after yet another line was requested, is not adopted.
  EXPECT_TRUE(rig.core.on_new_reference());
  ASSERT_TRUE(rig.core.worker().run_pending());
  EXPECT_EQ(rig.core.poll(rig.now).kind, Kind::superseded);
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::refits_superseded), 1u);
}

TEST(ReidentCore, AnOutcomeJudgedAgainstAReplacedSetIsNotAdopted) {
  Rig rig;
  rig.advance();
  rig.core.poll(rig.now);  // job judged against version 1
  // Meanwhile hystloop-identify publishes version 4.
  EXPECT_EQ(rig.core.on_params(rig.initial, 4, 0x1de, true, "identify@lab"), ParamsOffer::adopted);
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
  const std::int64_t own = rig.core.in_use().own_publisher_id();
  EXPECT_NE(own, 0);
  EXPECT_EQ(rig.core.on_params(next.candidate, 5, own, true, "reident@test"), ParamsOffer::echo);
}

TEST(ReidentCore, GarbageIsRefusedCountedAndNeverAdopted) {
  Rig rig;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // A block refused on the wire (NaN) poisons every window that holds it.
  rig.advance();
  rig.core.on_refused_block(10, rig.now);
  rig.seq += 10;
  EXPECT_EQ(rig.refit().status, FitStatus::poisoned_window);
  // A NaN that reached the core some other way does the same.
  SensorTick bad = sample_tick(1.0, nan);
  bad.seq = rig.seq++;
  rig.core.on_sample(bad, rig.now);
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

TEST(ReidentCore, SkipsFlaggedTicksAndCountsGapsAndRestarts) {
  Rig rig;
  rig.tick(0);
  rig.tick(1, kSafeState | kSimulated);
  rig.tick(2, kSensorFault);
  rig.tick(3, kSaturated | kLateCommand);
  rig.tick(10);                            // 6 missing
  rig.tick(12);                            // 1 missing
  rig.core.on_refused_block(1, rig.now);   // 13 (NaN, refused on the wire) ...
  rig.tick(14);                            // ... is no gap
  rig.core.on_refused_block(1, rig.now);   // 15
  rig.tick(17);                            // 16 missing
  rig.core.on_refused_block(10, rig.now);  // 18 .. 27, a block the size of the bridge's
  rig.tick(28);                            // no gap
  rig.core.on_refused_block(10, rig.now);  // 29 .. 38
  rig.tick(40);                            // 39 missing
  rig.tick(0);                             // the bridge restarted
  const ReidentCounters& c = rig.core.counters();
  EXPECT_EQ(c.get(ReidentCounter::samples_fed), 13u);  // nine ticks and four poison markers
  EXPECT_EQ(c.get(ReidentCounter::non_finite), 4u);
  EXPECT_EQ(c.get(ReidentCounter::skipped_safe_state), 1u);
  EXPECT_EQ(c.get(ReidentCounter::skipped_sensor_fault), 1u);
  EXPECT_EQ(c.get(ReidentCounter::seq_gaps), 4u);
  EXPECT_EQ(c.get(ReidentCounter::samples_missed), 9u);
  EXPECT_EQ(c.get(ReidentCounter::seq_restarts), 1u);
  // Counters only count up (RESET_COUNTERS is the service's CounterSet baseline).
  rig.tick(1);
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::samples_fed), 14u);
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::seq_gaps), 4u);
}

TEST(ReidentCore, ABlockIsItsTicksInOrder) {
  Rig rig;
  sensor_block_t b = testdata::reserved_sensor_block();
  const std::vector<double> u{1.0, 2.0, 3.0, 4.0}, y{1e-9, 2e-9, 3e-9, 4e-9};
  testdata::fill_sensor_block(b, 100, rig.now, u, y, 0, 4);
  b.flags[1] = kSafeState;
  b.flags[2] = kSensorFault;
  rig.core.on_sensor_block(b, rig.now);
  testdata::fill_sensor_block(b, 110, rig.now, u, y, 0, 4);  // 104 .. 109 missing
  rig.core.on_sensor_block(b, rig.now);
  const ReidentCounters& c = rig.core.counters();
  EXPECT_EQ(c.get(ReidentCounter::samples_fed), 6u);
  EXPECT_EQ(c.get(ReidentCounter::skipped_safe_state), 1u);
  EXPECT_EQ(c.get(ReidentCounter::skipped_sensor_fault), 1u);
  EXPECT_EQ(c.get(ReidentCounter::seq_gaps), 1u);
  EXPECT_EQ(c.get(ReidentCounter::samples_missed), 6u);
  EXPECT_TRUE(rig.core.seen_samples());
}

TEST(ReidentCore, ABlockWithoutItsAxisIsNotFittedButCountedAsRefused) {
  ReidentOptions options = testdata::small_reident_options(testdata::piezo_truth());
  options.axis = 2;  // z
  ReidentCore core{options, "reident@test", /*start_thread=*/false};
  sensor_block_t xy = testdata::reserved_sensor_block();
  begin_block(xy, 100, 10 * kSecond, 1e-4, 2);
  for (std::int64_t k = 100; k < 104; ++k) {
    const std::array<SensorTick, 2> axes{SensorTick{.seq = k, .u_V = 1.0, .y_m = 1e-9},
                                         SensorTick{.seq = k, .u_V = 2.0, .y_m = 2e-9}};
    ASSERT_TRUE(append_tick(xy, axes));
  }
  EXPECT_FALSE(core.on_sensor_block(xy, 10 * kSecond));
  const ReidentCounters& c = core.counters();
  EXPECT_EQ(c.get(ReidentCounter::sensor_blocks_wrong_axes), 1u);
  // Like a block refused on the wire: one poison marker, no sample of either axis.
  EXPECT_EQ(c.get(ReidentCounter::samples_fed), 1u);
  EXPECT_EQ(c.get(ReidentCounter::non_finite), 1u);
}

TEST(ReidentCore, TheAppliedVersionIsTheCommandsAtTheSampleTickAndNumberingGoesAboveIt) {
  Rig rig;
  command_block_t cmd = testdata::reserved_command_block();
  // The compensator runs 300 ticks ahead and swaps to version 7 (a set published before we
  // started: HX_PARAMS will not repeat it) at tick 250.
  testdata::fill_command_block(cmd, 0, 250, 3);
  rig.core.on_command_block(cmd);
  testdata::fill_command_block(cmd, 250, 50, 7);
  rig.core.on_command_block(cmd);
  rig.advance(0.02);  // ticks 0 .. 199
  EXPECT_EQ(rig.core.in_use().applied_version(), 3);
  rig.advance(0.006);  // .. 259
  EXPECT_EQ(rig.core.in_use().applied_version(), 7);
  EXPECT_EQ(rig.core.in_use().version(), 1);  // judged against the configured set: 7's parameters are unknown
  // An accepted refit is published above every version the compensator applied.
  rig.advance();
  const RefitDecision d = rig.refit();
  ASSERT_EQ(d.kind, Kind::accepted) << to_string(d.status);
  EXPECT_EQ(d.version, 8);
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::command_versions_dropped), 0u);
}

TEST(ReidentCore, StaleWhenNoSampleForLongerThanConfigured) {
  Rig rig;
  EXPECT_TRUE(rig.core.stale(rig.now));  // none yet
  EXPECT_FALSE(rig.core.seen_samples());
  rig.core.on_sample(sample_tick(0.0, 0.0), rig.now);
  EXPECT_FALSE(rig.core.stale(rig.now + kSecond));
  EXPECT_TRUE(rig.core.stale(rig.now + kSecond + 1));
  EXPECT_DOUBLE_EQ(rig.core.seconds_since_sample(rig.now + 2 * kSecond), 2.0);
}

TEST(ReidentCore, TheBlockPathAllocatesNothing) {
  // What the service's handlers do per message: blocks decoded into reserved storage, walked
  // tick by tick (sensor and command), refused blocks, and polls with a job in flight.
  Rig rig;
  const auto rec = testdata::sine_record(rig.truth, 12, 0.6);
  rig.stream(rec);
  rig.core.poll(rig.now);  // a job in flight: snapshotted
  command_block_t cmd = testdata::reserved_command_block();
  testing::AllocationCounter counter;
  for (std::size_t k = 0; k < rec.u.size(); k += kBlockTicks) {
    testdata::fill_command_block(cmd, rig.seq + 300, kBlockTicks, 2 + static_cast<std::int32_t>(k / 2000));
    rig.core.on_command_block(cmd);
    testdata::fill_sensor_block(rig.block, rig.seq, rig.now, rec.u, rec.y, k, kBlockTicks,
                                k % 70 == 0 ? kSafeState : 0);
    rig.core.on_sensor_block(rig.block, rig.now);
    rig.seq += static_cast<std::int64_t>(kBlockTicks);
    if (k % 1000 == 0) {
      rig.core.on_refused_block(static_cast<std::int64_t>(kBlockTicks), rig.now);
      rig.seq += static_cast<std::int64_t>(kBlockTicks);
    }
  }
  rig.core.poll(rig.now);  // in flight: nothing to do
  const std::size_t allocations = counter.allocations();
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(rig.core.counters().get(ReidentCounter::seq_gaps), 0u);
  EXPECT_GE(rig.core.in_use().applied_version(), 2);
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
