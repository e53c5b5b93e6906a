#include "core/periodic_timer.hpp"

#include <gtest/gtest.h>
#include <sys/prctl.h>

#include <random>

#include "core/errors.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

constexpr std::int64_t kPeriod = 100'000;  // 10 kHz

TEST(DeadlineSchedule, OnTimeWakesServeEveryTick) {
  DeadlineSchedule s(1'000'000, kPeriod);
  for (std::uint64_t k = 0; k < 100; ++k) {
    ASSERT_EQ(s.next_deadline_ns(), 1'000'000 + static_cast<std::int64_t>(k) * kPeriod);
    const TickInfo t = s.on_wake(s.next_deadline_ns() + 7'000);
    EXPECT_EQ(t.tick, k);
    EXPECT_EQ(t.lateness_ns, 7'000);
    EXPECT_EQ(t.skipped, 0u);
  }
}

TEST(DeadlineSchedule, OverrunServesLatestDeadlineAndCountsSkipped) {
  DeadlineSchedule s(0, kPeriod);
  (void)s.on_wake(0);  // tick 0 on time; tick 1 is due at 100 us
  // Back 3.5 periods after tick 1 was due: ticks 1, 2, 3 have passed, 4 has passed
  // too (at 400 us <= 450 us). Serve 4 late by 50 us, skip 1..3.
  const TickInfo t = s.on_wake(450'000);
  EXPECT_EQ(t.tick, 4u);
  EXPECT_EQ(t.deadline_ns, 400'000);
  EXPECT_EQ(t.lateness_ns, 50'000);
  EXPECT_EQ(t.skipped, 3u);
  // No burst: the next tick is due on the grid, one period later.
  EXPECT_EQ(s.next_tick(), 5u);
  EXPECT_EQ(s.next_deadline_ns(), 500'000);
}

TEST(DeadlineSchedule, WakingExactlyOnALaterDeadlineServesIt) {
  DeadlineSchedule s(0, kPeriod);
  const TickInfo t = s.on_wake(2 * kPeriod);
  EXPECT_EQ(t.tick, 2u);
  EXPECT_EQ(t.lateness_ns, 0);
  EXPECT_EQ(t.skipped, 2u);
}

TEST(DeadlineSchedule, EarlyWakeServesTheNextDeadlineWithNegativeLateness) {
  DeadlineSchedule s(1'000, kPeriod);
  const TickInfo t = s.on_wake(900);
  EXPECT_EQ(t.tick, 0u);
  EXPECT_EQ(t.lateness_ns, -100);
  EXPECT_EQ(t.skipped, 0u);
}

TEST(DeadlineSchedule, RandomWakesAccountForEveryDeadline) {
  // Property: served + skipped == index of the last tick + 1, lateness in [0, period).
  std::mt19937_64 rng(42);
  std::uniform_int_distribution<std::int64_t> delay(0, 5 * kPeriod);
  DeadlineSchedule s(0, kPeriod);
  std::uint64_t served = 0, skipped = 0;
  TickInfo last;
  for (int i = 0; i < 10'000; ++i) {
    last = s.on_wake(s.next_deadline_ns() + delay(rng));
    ++served;
    skipped += last.skipped;
    ASSERT_GE(last.lateness_ns, 0);
    ASSERT_LT(last.lateness_ns, kPeriod);
  }
  EXPECT_EQ(served + skipped, last.tick + 1);
}

TEST(DeadlineSchedule, ReanchorKeepsTickIndices) {
  DeadlineSchedule s(0, kPeriod);
  (void)s.on_wake(0);
  (void)s.on_wake(kPeriod);
  s.reanchor(10'000'000);
  EXPECT_EQ(s.next_tick(), 2u);
  EXPECT_EQ(s.next_deadline_ns(), 10'000'000);
  const TickInfo t = s.on_wake(10'000'000);
  EXPECT_EQ(t.tick, 2u);
  EXPECT_EQ(t.skipped, 0u);
}

TEST(DeadlineSchedule, RefusesNonPositivePeriod) {
  EXPECT_THROW(DeadlineSchedule(0, 0), ParameterError);
  EXPECT_THROW(DeadlineSchedule(0, -5), ParameterError);
  EXPECT_THROW(PeriodicTimer(0), ParameterError);
}

TEST(PeriodicTimer, RateConversion) {
  EXPECT_EQ(period_ns_from_rate_hz(10'000.0), 100'000);
  EXPECT_EQ(period_ns_from_rate_hz(1.0), 1'000'000'000);
  EXPECT_THROW(period_ns_from_rate_hz(0.0), ParameterError);
  EXPECT_THROW(period_ns_from_rate_hz(-1.0), ParameterError);
  EXPECT_THROW(period_ns_from_rate_hz(1e10), ParameterError);
}

// Real sleeps below: on a loaded machine any wake may come late and skip, so the
// checks are relative to what the previous wake reported.
TEST(PeriodicTimer, SleepsToTheDeadlineAndCountsAnOverrun) {
  constexpr std::int64_t kMs = 1'000'000;
  PeriodicTimer timer(kMs);
  const TickInfo first = timer.wait_next();
  EXPECT_GE(first.wake_ns, first.deadline_ns);  // never early
  EXPECT_EQ(first.tick, first.skipped);
  // Busy past 3.5 more periods: the next wait returns at once for a later tick.
  const std::int64_t until = first.deadline_ns + 4 * kMs + kMs / 2;
  while (monotonic_ns() < until) {
  }
  const TickInfo late = timer.wait_next();
  EXPECT_GE(late.tick, first.tick + 4);
  EXPECT_EQ(late.skipped, late.tick - first.tick - 1);
  EXPECT_GE(late.lateness_ns, 0);
  EXPECT_LT(late.lateness_ns, kMs);
  EXPECT_EQ(timer.ticks_served(), 2u);
  EXPECT_EQ(timer.skipped_total(), first.skipped + late.skipped);
  EXPECT_EQ(timer.lateness_stats().count(), 2u);
}

TEST(PeriodicTimer, FirstWaitTightensTheThreadTimerSlack) {
  ASSERT_TRUE(set_thread_timer_slack_ns(50'000));
  EXPECT_EQ(::prctl(PR_GET_TIMERSLACK, 0, 0, 0, 0), 50'000);
  PeriodicTimer timer(100'000);
  (void)timer.wait_next();
  EXPECT_EQ(::prctl(PR_GET_TIMERSLACK, 0, 0, 0, 0), 1);
  EXPECT_FALSE(set_thread_timer_slack_ns(0));
}

TEST(PeriodicTimer, RestartIsNotCountedAsSkipped) {
  constexpr std::int64_t kPeriod50ms = 50'000'000;  // long: a busy machine may stall us a while
  PeriodicTimer timer(kPeriod50ms);
  const TickInfo first = timer.wait_next();
  const std::int64_t until = monotonic_ns() + 120'000'000;  // pause > 2 periods
  while (monotonic_ns() < until) {
  }
  timer.restart();
  const TickInfo t = timer.wait_next();
  EXPECT_EQ(t.tick, first.tick + 1);
  EXPECT_EQ(t.skipped, 0u);
}

// Real time at 10 kHz for one second. The machine is shared: only the accounting
// and the ordering of the figures are checked, never their size.
TEST(PeriodicTimer, Keeps10kHzForOneSecondWithEveryTickAccountedFor) {
  constexpr std::uint64_t kTicks = 10'000;
  const std::int64_t start = monotonic_ns();  // before the timer: its grid starts later
  PeriodicTimer timer(kPeriod);
  std::uint64_t served = 0, skipped = 0;
  TickInfo t;
  testing::AllocationCounter counter;
  do {
    t = timer.wait_next();
    ++served;
    skipped += t.skipped;
  } while (t.tick + 1 < kTicks);
  const std::int64_t elapsed = monotonic_ns() - start;
  EXPECT_EQ(counter.allocations(), 0u);

  // Every deadline that came due is accounted for, served or skipped; the last
  // wake may itself have skipped past deadline 9'999.
  EXPECT_GE(t.tick + 1, kTicks);
  EXPECT_EQ(served + skipped, t.tick + 1);
  EXPECT_EQ(timer.ticks_served(), served);
  EXPECT_EQ(timer.skipped_total(), skipped);
  EXPECT_GE(elapsed, static_cast<std::int64_t>(kTicks) * kPeriod);  // a full second passed

  const LatencyStats& lat = timer.lateness_stats();
  ASSERT_EQ(lat.count(), served);
  const auto s = lat.summary();
  EXPECT_GE(s.min_ns, 0.0);
  EXPECT_LE(s.p50_ns, s.p99_ns);
  EXPECT_LE(s.p99_ns, s.p999_ns);
  EXPECT_LE(s.p999_ns, s.max_ns);
  RecordProperty("served", static_cast<int>(served));
  RecordProperty("skipped", static_cast<int>(skipped));
  std::printf("10 kHz for 1 s: served %llu, skipped %llu, lateness p50 %.1f us, p99 %.1f us, max %.1f us\n",
              static_cast<unsigned long long>(served), static_cast<unsigned long long>(skipped), s.p50_ns / 1e3,
              s.p99_ns / 1e3, s.max_ns / 1e3);
}

}  // namespace
}  // namespace hystloop
