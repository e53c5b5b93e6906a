#include "logger/sequence_gap_detector.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "core/errors.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

using Outcome = SequenceGapDetector::Outcome;

TEST(SequenceGapDetector, InOrderStreamHasNoGaps) {
  SequenceGapDetector d;
  EXPECT_EQ(d.observe(5), Outcome::kFirst);
  for (std::int64_t k = 6; k < 1000; ++k) EXPECT_EQ(d.observe(k), Outcome::kInOrder);
  EXPECT_EQ(d.observed(), 995u);
  EXPECT_EQ(d.gap_events(), 0u);
  EXPECT_EQ(d.missing(), 0u);
  EXPECT_EQ(d.first_seq(), 5);
  EXPECT_EQ(d.last_seq(), 999);
}

TEST(SequenceGapDetector, GapCountsMissingTicksAndKeepsTheRange) {
  SequenceGapDetector d;
  d.observe(0);
  d.observe(1);
  EXPECT_EQ(d.observe(19), Outcome::kGap);  // 2..18 missing
  EXPECT_EQ(d.observe(20), Outcome::kInOrder);
  EXPECT_EQ(d.observe(22), Outcome::kGap);  // 21 missing
  EXPECT_EQ(d.gap_events(), 2u);
  EXPECT_EQ(d.missing(), 18u);
  ASSERT_EQ(d.kept_gap_count(), 2u);
  EXPECT_EQ(d.kept_gaps()[0].first_missing, 2);
  EXPECT_EQ(d.kept_gaps()[0].last_missing, 18);
  EXPECT_EQ(d.kept_gaps()[0].count(), 17u);
  EXPECT_EQ(d.kept_gaps()[1].first_missing, 21);
  EXPECT_EQ(d.kept_gaps()[1].last_missing, 21);
}

TEST(SequenceGapDetector, DuplicateAndLateMessagesAreCountedNotGaps) {
  SequenceGapDetector d(100);
  d.observe(10);
  d.observe(11);
  EXPECT_EQ(d.observe(11), Outcome::kDuplicate);
  EXPECT_EQ(d.observe(13), Outcome::kGap);
  EXPECT_EQ(d.observe(12), Outcome::kOutOfOrder);  // late: the gap stays counted
  EXPECT_EQ(d.observe(14), Outcome::kInOrder);     // last was kept at 13
  EXPECT_EQ(d.duplicates(), 1u);
  EXPECT_EQ(d.out_of_order(), 1u);
  EXPECT_EQ(d.missing(), 1u);
  EXPECT_EQ(d.last_seq(), 14);
}

TEST(SequenceGapDetector, LargeStepBackIsARestart) {
  SequenceGapDetector d(100);
  for (std::int64_t k = 0; k <= 500; ++k) d.observe(k);
  EXPECT_EQ(d.observe(400), Outcome::kOutOfOrder);  // 100 back: still "late"
  EXPECT_EQ(d.observe(399), Outcome::kRestart);     // 101 back: a restart
  EXPECT_EQ(d.observe(400), Outcome::kInOrder);
  EXPECT_EQ(d.observe(0), Outcome::kRestart);
  EXPECT_EQ(d.observe(1), Outcome::kInOrder);
  EXPECT_EQ(d.restarts(), 2u);
  EXPECT_EQ(d.gap_events(), 0u);
  EXPECT_EQ(d.last_seq(), 1);
}

TEST(SequenceGapDetector, KeepsOnlyTheFirstGapsButCountsAll) {
  SequenceGapDetector d;
  std::int64_t seq = 0;
  d.observe(seq);
  for (int i = 0; i < 20; ++i) d.observe(seq += 3);  // two missing each time
  EXPECT_EQ(d.gap_events(), 20u);
  EXPECT_EQ(d.missing(), 40u);
  EXPECT_EQ(d.kept_gap_count(), SequenceGapDetector::kKeptGaps);
  EXPECT_EQ(d.kept_gaps()[SequenceGapDetector::kKeptGaps - 1].first_missing, 22);
}

TEST(SequenceGapDetector, ExtremeValuesDoNotOverflow) {
  constexpr auto kMin = std::numeric_limits<std::int64_t>::min();
  constexpr auto kMax = std::numeric_limits<std::int64_t>::max();
  SequenceGapDetector d;
  d.observe(kMin);
  EXPECT_EQ(d.observe(kMax), Outcome::kGap);
  EXPECT_EQ(d.missing(), std::numeric_limits<std::uint64_t>::max() - 1);
  EXPECT_EQ(d.observe(kMin), Outcome::kRestart);
}

TEST(SequenceGapDetector, RefusesANonPositiveThreshold) {
  EXPECT_THROW(SequenceGapDetector(0), ParameterError);
  try {
    SequenceGapDetector d(-3);
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "restart_threshold");
  }
}

// Property: drop a random subset of 0..N-1 (never the first), feed the rest in order;
// the detector's counts equal the runs and sizes of what was dropped.
TEST(SequenceGapDetector, SeededRandomDropsAreCountedExactly) {
  std::mt19937_64 rng(20240611);
  for (int trial = 0; trial < 200; ++trial) {
    const std::int64_t n = 1 + static_cast<std::int64_t>(rng() % 5000);
    const double p_drop = std::uniform_real_distribution<double>(0.0, 0.3)(rng);
    std::bernoulli_distribution drop(p_drop);
    std::vector<bool> kept(static_cast<std::size_t>(n), true);
    for (std::int64_t k = 1; k < n; ++k) kept[static_cast<std::size_t>(k)] = !drop(rng);
    std::int64_t last_kept = 0;
    for (std::int64_t k = 0; k < n; ++k) if (kept[static_cast<std::size_t>(k)]) last_kept = k;

    std::uint64_t runs = 0, missing = 0;
    for (std::int64_t k = 1; k <= last_kept; ++k) {
      if (!kept[static_cast<std::size_t>(k)]) {
        ++missing;
        if (kept[static_cast<std::size_t>(k - 1)]) ++runs;
      }
    }
    SequenceGapDetector d;
    const hystloop::testing::AllocationCounter allocations;
    for (std::int64_t k = 0; k < n; ++k) if (kept[static_cast<std::size_t>(k)]) d.observe(k);
    EXPECT_EQ(allocations.allocations(), 0u);
    ASSERT_EQ(d.gap_events(), runs) << "trial " << trial;
    ASSERT_EQ(d.missing(), missing) << "trial " << trial;
    EXPECT_EQ(d.last_seq(), last_kept);
    std::uint64_t kept_sum = 0;
    for (std::size_t g = 0; g < d.kept_gap_count(); ++g) {
      for (std::int64_t k = d.kept_gaps()[g].first_missing; k <= d.kept_gaps()[g].last_missing; ++k) {
        ASSERT_FALSE(kept[static_cast<std::size_t>(k)]);
      }
      kept_sum += d.kept_gaps()[g].count();
    }
    if (runs <= SequenceGapDetector::kKeptGaps) {
      EXPECT_EQ(kept_sum, missing);
    }
  }
}

}  // namespace
}  // namespace hystloop
