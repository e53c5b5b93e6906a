// VersionTimeline: the params_version of HX_COMMAND by tick, looked up at a sample's tick
// while the commands run ahead of it; restarts, re-plans, reordering, overflow, no allocation.
#include "reident/version_timeline.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

constexpr std::int32_t kUnknown = VersionTimeline::kUnknown;

// Records ticks first .. last (inclusive) with one version, as a command block would.
void record_ticks(VersionTimeline& t, std::int64_t first, std::int64_t last, std::int32_t version) {
  for (std::int64_t s = first; s <= last; ++s) t.record(s, version);
}

TEST(VersionTimeline, UnknownUntilACommandAtOrBeforeTheTick) {
  VersionTimeline t;
  EXPECT_EQ(t.at(0), kUnknown);
  record_ticks(t, 10, 19, 3);
  EXPECT_EQ(t.at(9), kUnknown);
  EXPECT_EQ(t.at(10), 3);
  EXPECT_EQ(t.at(19), 3);
  EXPECT_EQ(t.at(500), 3);  // no command for it yet: the bridge holds the last one
  EXPECT_EQ(t.size(), 1u);  // one change point for ten ticks
}

TEST(VersionTimeline, TheVersionAtASampleIsThatOfTheCommandForItsTickNotTheLastBlocks) {
  VersionTimeline t;
  // The compensator has planned 300 ticks ahead; the swap to version 2 happens at tick 250.
  record_ticks(t, 0, 249, 1);
  record_ticks(t, 250, 299, 2);
  EXPECT_EQ(t.at(0), 1);
  EXPECT_EQ(t.at(200), 1);  // sampled now: still version 1, though the last block says 2
  EXPECT_EQ(t.at(249), 1);
  EXPECT_EQ(t.at(250), 2);
  EXPECT_EQ(t.at(299), 2);
  EXPECT_EQ(t.size(), 2u);
}

TEST(VersionTimeline, ForgettingKeepsTheChangePointThatCoversTheSample) {
  VersionTimeline t;
  record_ticks(t, 0, 99, 1);
  record_ticks(t, 100, 199, 2);
  record_ticks(t, 200, 299, 3);
  t.forget_before(150);
  EXPECT_EQ(t.size(), 2u);
  EXPECT_EQ(t.at(150), 2);
  EXPECT_EQ(t.at(250), 3);
  EXPECT_EQ(t.at(50), kUnknown);  // no sample goes back there
  t.forget_before(150);           // idempotent
  EXPECT_EQ(t.at(100), 2);
  t.forget_before(10'000);
  EXPECT_EQ(t.size(), 1u);
  EXPECT_EQ(t.at(10'000), 3);
}

TEST(VersionTimeline, ARestartedTickNumberingReplacesTheOldOneAtOnce) {
  VersionTimeline t;
  record_ticks(t, 0, 2999, 1);
  record_ticks(t, 3000, 5000, 3);
  // The bridge restarted: commands for ticks from 0 again, the compensator still on version 3 ...
  record_ticks(t, 0, 299, 3);
  EXPECT_EQ(t.at(100), 3);
  EXPECT_EQ(t.at(4000), 3);  // ... and the old plan for ticks >= 3000 is gone
  EXPECT_EQ(t.size(), 1u);
  // Restarted with version 1 (a restarted compensator): the old version 3 at 3000 must not come back.
  VersionTimeline u;
  record_ticks(u, 0, 2999, 1);
  record_ticks(u, 3000, 5000, 3);
  record_ticks(u, 10, 299, 1);
  EXPECT_EQ(u.at(4000), 1);
}

TEST(VersionTimeline, ANewerPlanForTicksAlreadyPlannedWins) {
  VersionTimeline t;
  record_ticks(t, 100, 199, 2);
  record_ticks(t, 150, 199, 4);  // re-planned from 150 on
  EXPECT_EQ(t.at(120), 2);
  EXPECT_EQ(t.at(150), 4);
  EXPECT_EQ(t.at(199), 4);
  t.record(150, 2);  // and back (the same tick sent again with its first version)
  EXPECT_EQ(t.at(150), 2);
  EXPECT_EQ(t.size(), 1u);
}

TEST(VersionTimeline, ABlockReorderedAcrossAChangeHoldsTheOlderVersionUntilTheNextBlock) {
  VersionTimeline t;
  record_ticks(t, 100, 109, 1);
  record_ticks(t, 120, 129, 2);  // overtook 110 .. 119
  record_ticks(t, 110, 119, 1);
  EXPECT_EQ(t.at(115), 1);
  EXPECT_EQ(t.at(125), 1);  // the documented loss: one block at the older version ...
  record_ticks(t, 130, 139, 2);
  EXPECT_EQ(t.at(135), 2);  // ... until the next block
  // Reordered without a change in between: nothing lost.
  VersionTimeline u;
  record_ticks(u, 100, 109, 5);
  record_ticks(u, 120, 129, 5);
  record_ticks(u, 110, 119, 5);
  EXPECT_EQ(u.at(125), 5);
  EXPECT_EQ(u.size(), 1u);
}

TEST(VersionTimeline, AFullRingDropsItsOldestChangePointAndCountsIt) {
  VersionTimeline t;
  const std::size_t n = VersionTimeline::kCapacity + 5;
  for (std::size_t i = 0; i < n; ++i) t.record(static_cast<std::int64_t>(i), static_cast<std::int32_t>(i % 2));
  EXPECT_EQ(t.size(), VersionTimeline::kCapacity);
  EXPECT_EQ(t.overflows(), 5u);
  EXPECT_EQ(t.at(4), kUnknown);  // dropped
  EXPECT_EQ(t.at(5), 1);
  EXPECT_EQ(t.at(static_cast<std::int64_t>(n - 1)), static_cast<std::int32_t>((n - 1) % 2));
  t.clear();
  EXPECT_EQ(t.at(static_cast<std::int64_t>(n)), kUnknown);
}

// Seeded property: commands in blocks of random length, up to a random horizon ahead of the
// samples, versions switching at random ticks; every sample's version is the planned one.
TEST(VersionTimeline, MatchesThePlanAtEverySampleWhileCommandsRunAhead) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_int_distribution<int> block_len(1, 40), horizon(0, 600), change(0, 399), step(1, 3);
    constexpr std::int64_t kTicks = 20'000;
    std::vector<std::int32_t> plan(kTicks);
    std::int32_t v = 1;
    for (std::int64_t s = 0; s < kTicks; ++s) {
      if (change(rng) == 0) v += step(rng);
      plan[static_cast<std::size_t>(s)] = v;
    }
    VersionTimeline t;
    std::int64_t sent = 0;  // next tick without a command
    for (std::int64_t sample = 0; sample < kTicks; ++sample) {
      const std::int64_t ahead = std::min<std::int64_t>(kTicks, sample + 1 + horizon(rng));
      while (sent < ahead) {
        const std::int64_t end = std::min<std::int64_t>(ahead, sent + block_len(rng));
        for (; sent < end; ++sent) t.record(sent, plan[static_cast<std::size_t>(sent)]);
      }
      ASSERT_EQ(t.at(sample), plan[static_cast<std::size_t>(sample)]) << "seed " << seed << " tick " << sample;
      t.forget_before(sample);
      ASSERT_LE(t.size(), 20u) << "seed " << seed;  // a few changes within a horizon, not the whole history
    }
    EXPECT_EQ(t.overflows(), 0u);
  }
}

TEST(VersionTimeline, AllocatesNothing) {
  VersionTimeline t;
  std::int64_t known = 0;
  testing::AllocationCounter counter;
  for (std::int64_t s = 0; s < 100'000; ++s) {
    t.record(s + 300, static_cast<std::int32_t>(s / 1000));
    if (t.at(s) != kUnknown) ++known;
    t.forget_before(s);
  }
  record_ticks(t, 0, 10, 1);  // a restart
  const std::size_t allocations = counter.allocations();
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(known, 100'000 - 300);
}

}  // namespace
}  // namespace hystloop
