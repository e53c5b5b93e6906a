#include "core/sequence_gap_detector.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "core/errors.hpp"
#include "core/ticks.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

using Outcome = SequenceGapDetector::Outcome;

TEST(SequenceGapDetector, ContiguousBlocksHaveNoGaps) {
  SequenceGapDetector d;
  EXPECT_EQ(d.observe(5, 10), Outcome::kFirst);
  for (std::int64_t first = 15; first < 1005; first += 10) EXPECT_EQ(d.observe(first, 10), Outcome::kInOrder);
  EXPECT_EQ(d.observe(1005, 1), Outcome::kInOrder);  // a block of one tick
  EXPECT_EQ(d.observe(1006, 3), Outcome::kInOrder);
  EXPECT_EQ(d.observed(), 102u);
  EXPECT_EQ(d.ticks(), 1004u);
  EXPECT_EQ(d.gap_events(), 0u);
  EXPECT_EQ(d.missing(), 0u);
  EXPECT_EQ(d.first_seq(), 5);
  EXPECT_EQ(d.last_seq(), 1008);
}

TEST(SequenceGapDetector, AGapBetweenBlocksCountsTheMissingTicksAndKeepsTheRange) {
  SequenceGapDetector d;
  d.observe(0, 10);
  d.observe(10, 10);
  EXPECT_EQ(d.observe(37, 10), Outcome::kGap);  // 20..36 missing
  EXPECT_EQ(d.observe(47, 10), Outcome::kInOrder);
  EXPECT_EQ(d.observe(58, 3), Outcome::kGap);  // 57 missing
  EXPECT_EQ(d.gap_events(), 2u);
  EXPECT_EQ(d.missing(), 18u);
  ASSERT_EQ(d.kept_gap_count(), 2u);
  EXPECT_EQ(d.kept_gaps()[0].first_missing, 20);
  EXPECT_EQ(d.kept_gaps()[0].last_missing, 36);
  EXPECT_EQ(d.kept_gaps()[0].count(), 17u);
  EXPECT_EQ(d.kept_gaps()[1].first_missing, 57);
  EXPECT_EQ(d.kept_gaps()[1].last_missing, 57);
  EXPECT_EQ(d.last_seq(), 60);
}

TEST(SequenceGapDetector, DuplicateOverlappingAndLateBlocksAreCountedNotGaps) {
  SequenceGapDetector d(100);
  d.observe(10, 10);
  d.observe(20, 10);
  EXPECT_EQ(d.observe(20, 10), Outcome::kDuplicate);  // the last block again
  EXPECT_EQ(d.observe(25, 10), Outcome::kOverlap);    // 25..29 again, 30..34 new
  EXPECT_EQ(d.last_seq(), 34);
  EXPECT_EQ(d.observe(40, 10), Outcome::kGap);        // 35..39 missing
  EXPECT_EQ(d.observe(35, 5), Outcome::kOutOfOrder);  // late: the gap stays counted
  EXPECT_EQ(d.observe(12, 3), Outcome::kOutOfOrder);  // inside an old block
  EXPECT_EQ(d.observe(50, 10), Outcome::kInOrder);    // last was kept at 49
  EXPECT_EQ(d.duplicates(), 1u);
  EXPECT_EQ(d.overlaps(), 1u);
  EXPECT_EQ(d.overlap_ticks(), 5u);
  EXPECT_EQ(d.out_of_order(), 2u);
  EXPECT_EQ(d.gap_events(), 1u);
  EXPECT_EQ(d.missing(), 5u);
  EXPECT_EQ(d.last_seq(), 59);
}

TEST(SequenceGapDetector, LargeStepBackIsARestart) {
  SequenceGapDetector d(100);
  for (std::int64_t first = 0; first <= 500; first += 10) d.observe(first, 10);  // up to 509
  EXPECT_EQ(d.observe(409, 10), Outcome::kOutOfOrder);                           // 100 back: still "late"
  EXPECT_EQ(d.observe(408, 10), Outcome::kRestart);                              // 101 back: a restart
  EXPECT_EQ(d.observe(418, 10), Outcome::kInOrder);
  EXPECT_EQ(d.observe(0, 10), Outcome::kRestart);
  EXPECT_EQ(d.observe(10, 10), Outcome::kInOrder);
  EXPECT_EQ(d.restarts(), 2u);
  EXPECT_EQ(d.gap_events(), 0u);
  EXPECT_EQ(d.last_seq(), 19);
}

// Commands run ahead: a compensator that stalled or restarted starts again at a later tick.
// After enough silence that jump is a resume (its ticks counted as skipped), not a gap.
TEST(SequenceGapDetector, AForwardJumpAfterSilenceIsAResumeWhenEnabled) {
  SequenceGapDetector d(10000, 50'000);
  d.observe(0, 10, 1'000'000);
  d.observe(10, 10, 1'001'000);
  EXPECT_EQ(d.observe(500, 10, 1'101'000), Outcome::kResume);   // 100 ms silent: 20..499 skipped
  EXPECT_EQ(d.observe(520, 10, 1'102'000), Outcome::kGap);      // 1 ms later: 510..519 lost
  EXPECT_EQ(d.observe(530, 10, 1'160'000), Outcome::kInOrder);  // silence without a jump: nothing
  EXPECT_EQ(d.resumes(), 1u);
  EXPECT_EQ(d.skipped(), 480u);
  EXPECT_EQ(d.gap_events(), 1u);
  EXPECT_EQ(d.missing(), 10u);
  ASSERT_EQ(d.kept_gap_count(), 1u);
  EXPECT_EQ(d.kept_gaps()[0].first_missing, 510);
  EXPECT_EQ(d.last_seq(), 539);

  SequenceGapDetector never(10000, 0);  // disabled: every jump is a gap
  never.observe(0, 10, 1'000'000);
  EXPECT_EQ(never.observe(500, 10, 9'000'000), Outcome::kGap);
  EXPECT_EQ(never.missing(), 490u);
  EXPECT_EQ(never.resumes(), 0u);
}

TEST(SequenceGapDetector, ARestartedCompensatorThatStartsEarlierOverlaps) {
  SequenceGapDetector d(10000, 50'000);
  for (std::int64_t first = 0; first < 1000; first += 10) d.observe(first, 10, 1'000'000 + 100 * first);
  // It had sent up to 999; the new one plans from 900 on: ticks 900..999 again, then new ones.
  EXPECT_EQ(d.observe(900, 200, 2'000'000), Outcome::kOverlap);
  EXPECT_EQ(d.overlap_ticks(), 100u);
  EXPECT_EQ(d.observe(1100, 10, 2'001'000), Outcome::kInOrder);
  EXPECT_EQ(d.missing() + d.skipped(), 0u);
}

TEST(SequenceGapDetector, KeepsOnlyTheFirstGapsButCountsAll) {
  SequenceGapDetector d;
  std::int64_t first = 0;
  d.observe(first, 10);
  for (int i = 0; i < 20; ++i) d.observe(first += 12, 10);  // two ticks missing each time
  EXPECT_EQ(d.gap_events(), 20u);
  EXPECT_EQ(d.missing(), 40u);
  EXPECT_EQ(d.kept_gap_count(), SequenceGapDetector::kKeptGaps);
  EXPECT_EQ(d.kept_gaps()[SequenceGapDetector::kKeptGaps - 1].first_missing, 94);
}

TEST(SequenceGapDetector, TheLargestTicksTheContractAllowsDoNotOverflow) {
  SequenceGapDetector d;
  d.observe(0, 1);
  EXPECT_EQ(d.observe(kMaxTick, 1000), Outcome::kGap);  // the longest jump the contract allows
  EXPECT_EQ(d.missing(), static_cast<std::uint64_t>(kMaxTick) - 1);
  EXPECT_EQ(d.last_seq(), kMaxTick + 999);
  EXPECT_EQ(d.observe(kMaxTick, 1000), Outcome::kDuplicate);
  EXPECT_EQ(d.observe(0, 1), Outcome::kRestart);
  EXPECT_EQ(d.last_seq(), 0);
  EXPECT_EQ(d.violations(), 0u);
}

// Ticks the contract forbids (a gap counter wrapped to 1.69e19 with seq = INT64_MIN, then
// INT64_MAX): counted by their reason and kept out of the gap arithmetic altogether.
TEST(SequenceGapDetector, ForbiddenTicksAreCountedByReasonNotSummed) {
  using V = SequenceGapDetector::Violation;
  constexpr auto kMin = std::numeric_limits<std::int64_t>::min();
  constexpr auto kMax = std::numeric_limits<std::int64_t>::max();
  SequenceGapDetector d;
  EXPECT_EQ(d.observe(-5, 10), Outcome::kViolation);  // not even the first block
  EXPECT_FALSE(d.started());
  EXPECT_EQ(d.observe(100, 10), Outcome::kFirst);
  EXPECT_EQ(d.observe(kMin, 1), Outcome::kViolation);
  EXPECT_EQ(d.observe(-1, 10), Outcome::kViolation);
  EXPECT_EQ(d.observe(kMax, 1), Outcome::kViolation);          // a jump of 2^63 ticks
  EXPECT_EQ(d.observe(kMax - 5, 1000), Outcome::kViolation);   // seq + n_ticks overflows int64
  EXPECT_EQ(d.observe(kMaxTick + 1, 1), Outcome::kViolation);  // just above the contract's range
  EXPECT_EQ(d.observe(200, 0), Outcome::kViolation);
  EXPECT_EQ(d.observe(200, -3), Outcome::kViolation);
  EXPECT_EQ(d.observe(200, 1001), Outcome::kViolation);  // more than MAX_TICKS
  EXPECT_EQ(d.violations(V::kNegativeSeq), 3u);
  EXPECT_EQ(d.violations(V::kSeqAboveMax), 3u);
  EXPECT_EQ(d.violations(V::kTickCount), 3u);
  EXPECT_EQ(d.violations(), 9u);
  EXPECT_STREQ(SequenceGapDetector::to_string(V::kSeqAboveMax), "seq_above_max");
  // None of them was fed: the stream goes on from 109 as if they had not come.
  EXPECT_EQ(d.observed(), 1u);
  EXPECT_EQ(d.ticks(), 10u);
  EXPECT_EQ(d.first_seq(), 100);
  EXPECT_EQ(d.last_seq(), 109);
  EXPECT_EQ(d.observe(110, 10), Outcome::kInOrder);
  EXPECT_EQ(d.gap_events() + d.missing() + d.restarts() + d.out_of_order() + d.overlaps(), 0u);

  // Nor do they break a channel's silence: the resume is measured from the last block fed.
  SequenceGapDetector r(10000, 50'000);
  r.observe(0, 10, 1'000'000);
  EXPECT_EQ(r.observe(-1, 10, 1'099'000), Outcome::kViolation);
  EXPECT_EQ(r.observe(500, 10, 1'100'000), Outcome::kResume);
  EXPECT_EQ(r.skipped(), 490u);
}

// Forged but admissible ticks (0, then 2^53, again and again) saturate every counter instead
// of wrapping.
TEST(SequenceGapDetector, ForgedTicksSaturateTheCountersInsteadOfWrapping) {
  constexpr auto kTop = std::numeric_limits<std::uint64_t>::max();
  SequenceGapDetector d(1, 1);
  std::uint64_t last_missing = 0, last_skipped = 0;
  // 2^64 / (2^53 - 1) jumps of each kind are enough; 2100 go well past it.
  for (int i = 0; i < 2100; ++i) {
    d.observe(0, 1, 0);                                   // a restart
    ASSERT_EQ(d.observe(kMaxTick, 1, 0), Outcome::kGap);  // no silence: a gap of 2^53 - 1 ticks
    ASSERT_GE(d.missing(), last_missing) << i;            // never goes down (no wrap)
    last_missing = d.missing();
    d.observe(0, 1, 0);
    ASSERT_EQ(d.observe(kMaxTick, 1, 10), Outcome::kResume);  // after silence: skipped ticks
    ASSERT_GE(d.skipped(), last_skipped) << i;
    last_skipped = d.skipped();
  }
  EXPECT_EQ(d.missing(), kTop);
  EXPECT_EQ(d.skipped(), kTop);
  EXPECT_EQ(d.gap_events(), 2100u);
  EXPECT_EQ(d.restarts(), 4200u - 1);  // the first block is not one
  EXPECT_EQ(d.ticks(), 4u * 2100u);
}

// One tick at a time, as the compensator and the re-identifier use it: with kNeverRestarts a step
// back is a late tick whatever its size (the compensator's guard finds restarts); with threshold
// 0 every step back is a restart (nothing holds the re-identifier's blocks for confirmation).
TEST(SequenceGapDetector, TickByTickEitherNeverOrAlwaysRestarts) {
  SequenceGapDetector never(SequenceGapDetector::kNeverRestarts);
  EXPECT_EQ(never.observe(100, 1), Outcome::kFirst);
  EXPECT_EQ(never.observe(101, 1), Outcome::kInOrder);
  EXPECT_EQ(never.observe(105, 1), Outcome::kGap);
  EXPECT_EQ(never.observe(105, 1), Outcome::kDuplicate);
  EXPECT_EQ(never.observe(0, 1), Outcome::kOutOfOrder);  // 105 ticks back: still late
  EXPECT_EQ(never.observe(103, 1), Outcome::kOutOfOrder);
  EXPECT_EQ(never.observe(-1, 1), Outcome::kViolation);
  EXPECT_EQ(never.observe(106, 1), Outcome::kInOrder);
  EXPECT_EQ(never.missing(), 3u);
  EXPECT_EQ(never.restarts(), 0u);
  EXPECT_EQ(never.last_seq(), 106);

  SequenceGapDetector always(0);
  always.observe(40, 1);
  EXPECT_EQ(always.observe(40, 1), Outcome::kDuplicate);
  EXPECT_EQ(always.observe(39, 1), Outcome::kRestart);  // one tick back
  EXPECT_EQ(always.observe(40, 1), Outcome::kInOrder);  // the stream continues from there
  EXPECT_EQ(always.observe(0, 1), Outcome::kRestart);
  EXPECT_EQ(always.restarts(), 2u);
  EXPECT_EQ(always.missing(), 0u);
}

TEST(SequenceGapDetector, RefusesBadSettingsNamingTheField) {
  EXPECT_THROW(SequenceGapDetector(-1), ParameterError);
  try {
    SequenceGapDetector d(-3);
    ADD_FAILURE();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "restart_threshold");
  }
  try {
    SequenceGapDetector d(10, -1);
    ADD_FAILURE();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "resume_silence_us");
  }
}

// Property: a stream of blocks of random sizes, a random subset of them (never the first)
// dropped, the rest fed in order: the counts equal the runs of dropped blocks and the
// ticks they held, and the kept ranges are exactly dropped ticks.
TEST(SequenceGapDetector, SeededRandomDroppedBlocksAreCountedExactly) {
  std::mt19937_64 rng(20240611);
  for (int trial = 0; trial < 200; ++trial) {
    const int blocks = 1 + static_cast<int>(rng() % 1000);
    const double p_drop = std::uniform_real_distribution<double>(0.0, 0.3)(rng);
    std::bernoulli_distribution drop(p_drop);
    struct Block {
      std::int64_t first, n;
      bool kept;
    };
    std::vector<Block> stream;
    std::int64_t next = static_cast<std::int64_t>(rng() % 100000);
    for (int b = 0; b < blocks; ++b) {
      const auto n = 1 + static_cast<std::int64_t>(rng() % 12);
      stream.push_back({next, n, b == 0 || !drop(rng)});
      next += n;
    }
    std::size_t last_kept = 0;
    for (std::size_t b = 0; b < stream.size(); ++b)
      if (stream[b].kept) last_kept = b;
    std::uint64_t runs = 0, missing = 0;
    for (std::size_t b = 1; b <= last_kept; ++b) {
      if (stream[b].kept) continue;
      missing += static_cast<std::uint64_t>(stream[b].n);
      if (stream[b - 1].kept) ++runs;
    }

    SequenceGapDetector d;
    const hystloop::testing::AllocationCounter allocations;
    for (const Block& b : stream)
      if (b.kept) d.observe(b.first, b.n);
    EXPECT_EQ(allocations.allocations(), 0u);
    ASSERT_EQ(d.gap_events(), runs) << "trial " << trial;
    ASSERT_EQ(d.missing(), missing) << "trial " << trial;
    EXPECT_EQ(d.last_seq(), stream[last_kept].first + stream[last_kept].n - 1);
    std::uint64_t kept_sum = 0;
    for (std::size_t g = 0; g < d.kept_gap_count(); ++g) {
      for (std::int64_t t = d.kept_gaps()[g].first_missing; t <= d.kept_gaps()[g].last_missing; ++t) {
        for (const Block& b : stream) {
          if (t >= b.first && t < b.first + b.n) {
            ASSERT_FALSE(b.kept) << "tick " << t << " was received";
          }
        }
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
