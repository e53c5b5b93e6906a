// SequenceGuard: one forged (or corrupted) sensor block far ahead or behind is held and then
// ignored, the real blocks around it all taken; only kConfirmBlocks consecutive blocks that
// continue a new numbering, in quick succession, confirm a restart or a jump.
#include "loop/sequence_guard.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <random>

namespace hystloop {
namespace {

using V = SequenceGuard::Verdict;
constexpr std::int64_t kStep = 500;        // ticks (the compensator's horizon)
constexpr std::int64_t kWindow = 100'000;  // us
constexpr std::int64_t kBlock = 20;        // ticks per block, one block every 2 ms
constexpr std::int64_t kPeriod = 2'000;    // us

TEST(SequenceGuard, TheFirstBlockAndItsSuccessorsAreTaken) {
  SequenceGuard g(kStep, kWindow);
  EXPECT_EQ(g.check(123456, kBlock, 0), V::take);
  EXPECT_EQ(g.check(123476, kBlock, kPeriod), V::take);
  EXPECT_EQ(g.check(123496 + 3 * kBlock, kBlock, 2 * kPeriod), V::take);  // 3 blocks lost
  EXPECT_EQ(g.check(123496, kBlock, 3 * kPeriod), V::take);  // late: the compensator counts it out of order
  EXPECT_EQ(g.next_expected(), 123496 + 4 * kBlock);
  EXPECT_EQ(g.counters().held, 0u);
}

TEST(SequenceGuard, OneBlock900TicksAheadIsIgnoredAndTheRealBlocksAreTaken) {
  SequenceGuard g(kStep, kWindow);
  std::int64_t t = 0;
  for (std::int64_t s = 1000; s < 2000; s += kBlock) ASSERT_EQ(g.check(s, kBlock, t += kPeriod), V::take);
  EXPECT_EQ(g.check(2000 + 900, kBlock, t + 100), V::hold);  // forged
  for (std::int64_t s = 2000; s < 3000; s += kBlock) ASSERT_EQ(g.check(s, kBlock, t += kPeriod), V::take) << s;
  EXPECT_EQ(g.counters().held, 1u);
  EXPECT_EQ(g.counters().ignored, 1u);
  EXPECT_EQ(g.counters().jumps, 0u);
}

TEST(SequenceGuard, OneBlock5000TicksBehindDoesNotRestart) {
  SequenceGuard g(kStep, kWindow);
  std::int64_t t = 0;
  for (std::int64_t s = 50000; s < 51000; s += kBlock) ASSERT_EQ(g.check(s, kBlock, t += kPeriod), V::take);
  EXPECT_EQ(g.check(51000 - 5000, kBlock, t + 100), V::hold);
  EXPECT_EQ(g.check(51000 - 5000 + kBlock, kBlock, t + 200), V::hold);  // even two in a row
  for (std::int64_t s = 51000; s < 52000; s += kBlock) ASSERT_EQ(g.check(s, kBlock, t += kPeriod), V::take);
  EXPECT_EQ(g.counters().restarts, 0u);
  EXPECT_EQ(g.counters().ignored, 1u);
  EXPECT_EQ(g.counters().held, 2u);
}

TEST(SequenceGuard, ThreeConsecutiveBlocksConfirmARestart) {
  SequenceGuard g(kStep, kWindow);
  std::int64_t t = 0;
  for (std::int64_t s = 50000; s < 51000; s += kBlock) g.check(s, kBlock, t += kPeriod);
  t += 3'000'000;  // the bridge restarts: quiet, then its clock from 0
  EXPECT_EQ(g.check(0, kBlock, t += kPeriod), V::hold);
  EXPECT_EQ(g.check(kBlock, kBlock, t += kPeriod), V::hold);
  EXPECT_EQ(g.check(3 * kBlock, kBlock, t += kPeriod), V::restart);  // one lost between: still consistent
  EXPECT_EQ(g.check(4 * kBlock, kBlock, t += kPeriod), V::take);
  EXPECT_EQ(g.next_expected(), 5 * kBlock);
  EXPECT_EQ(g.counters().restarts, 1u);
  EXPECT_EQ(g.counters().held, 2u);
  EXPECT_EQ(g.counters().ignored, 0u);
}

TEST(SequenceGuard, ThreeConsecutiveBlocksConfirmAJumpAhead) {
  SequenceGuard g(kStep, kWindow);
  std::int64_t t = 0;
  for (std::int64_t s = 0; s < 1000; s += kBlock) g.check(s, kBlock, t += kPeriod);
  EXPECT_EQ(g.check(10000, kBlock, t += kPeriod), V::hold);
  EXPECT_EQ(g.check(10020, kBlock, t += kPeriod), V::hold);
  EXPECT_EQ(g.check(10040, kBlock, t += kPeriod), V::jump);
  EXPECT_EQ(g.check(1000, kBlock, t += kPeriod), V::hold);  // the old numbering is now the discontinuity
  EXPECT_EQ(g.check(10060, kBlock, t += kPeriod), V::take);
  EXPECT_EQ(g.counters().jumps, 1u);
  EXPECT_EQ(g.counters().ignored, 1u);
}

TEST(SequenceGuard, ABlockAtTheInt64CeilingIsHeldWithoutOverflow) {
  SequenceGuard g(kStep, kWindow);
  g.check(0, kBlock, 0);
  const std::int64_t top = std::numeric_limits<std::int64_t>::max();
  EXPECT_EQ(g.check(top - 5, kBlock, 1), V::hold);
  EXPECT_EQ(g.check(top - 1, kBlock, 2), V::hold);
  EXPECT_EQ(g.check(kBlock, kBlock, 3), V::take);
  EXPECT_EQ(g.counters().ignored, 1u);
}

TEST(SequenceGuard, ConsistentBlocksTooFarApartInTimeDoNotConfirm) {
  SequenceGuard g(kStep, kWindow);
  g.check(0, kBlock, 0);
  std::int64_t t = 0;
  for (int i = 0; i < 10; ++i) {  // one forged block a second, each continuing the last
    EXPECT_EQ(g.check(90000 + i * kBlock, kBlock, t += 1'000'000), V::hold) << i;
  }
  EXPECT_EQ(g.counters().ignored, 9u);
  EXPECT_EQ(g.counters().jumps, 0u);
}

// A real stream (lost blocks, short reorders) with forged blocks inserted at random: singles
// and runs of up to kConfirmBlocks - 1 consistent ones, far ahead or behind. Every real block is
// taken, nothing confirmed, every forged run ignored.
TEST(SequenceGuard, RandomInterleavingsOfForgedBlocksNeverDisturbTheRealStream) {
  for (std::uint32_t seed = 1; seed <= 200; ++seed) {
    std::mt19937 rng(seed);
    SequenceGuard g(kStep, kWindow);
    std::int64_t t = 1'000'000;
    std::int64_t s = std::uniform_int_distribution<std::int64_t>(0, 1'000'000)(rng);
    std::uint64_t runs = 0;
    std::uint64_t forged = 0;
    for (int i = 0; i < 400; ++i) {
      std::int64_t seq = s;
      if (rng() % 10 == 0) seq += kBlock * static_cast<std::int64_t>(1 + rng() % 5);  // lost blocks
      if (rng() % 20 == 0 && seq >= 2 * kBlock) seq -= 2 * kBlock;                    // a late one
      ASSERT_NE(g.check(seq, kBlock, t += kPeriod), V::hold) << "seed " << seed << " block " << i;
      s = std::max(s, seq) + kBlock;
      if (rng() % 7 == 0) {  // a forged run
        const std::int64_t off = std::uniform_int_distribution<std::int64_t>(kStep + 1, 100'000)(rng);
        std::int64_t f = (rng() % 2 == 0 || s < off) ? s + off : s - off;
        const int n = 1 + static_cast<int>(rng() % (SequenceGuard::kConfirmBlocks - 1));
        for (int k = 0; k < n; ++k, f += kBlock) {
          ASSERT_EQ(g.check(f, kBlock, t + k + 1), V::hold) << "seed " << seed;
          ++forged;
        }
        ++runs;
      }
    }
    EXPECT_EQ(g.counters().restarts + g.counters().jumps, 0u) << "seed " << seed;
    EXPECT_EQ(g.counters().held, forged);
    // The last run may still be pending when the stream ends.
    EXPECT_EQ(g.counters().ignored + (g.pending() ? 1u : 0u), runs) << "seed " << seed;
  }
}

// The same, with a real restart or jump somewhere: it is confirmed after kConfirmBlocks blocks
// whatever forged blocks came before, and the stream goes on from there.
TEST(SequenceGuard, RandomRealRestartsAreConfirmedAfterThreeBlocks) {
  for (std::uint32_t seed = 1; seed <= 100; ++seed) {
    std::mt19937 rng(seed);
    SequenceGuard g(kStep, kWindow);
    std::int64_t t = 0;
    std::int64_t s = 200'000;
    for (int i = 0; i < 50; ++i, s += kBlock) g.check(s, kBlock, t += kPeriod);
    if (rng() % 2 == 0) g.check(s + 50'000, kBlock, t += 10);  // a forged one before
    const bool back = rng() % 2 == 0;
    s = back ? static_cast<std::int64_t>(rng() % 1000) : s + 20'000;
    EXPECT_EQ(g.check(s, kBlock, t += kPeriod), V::hold);
    EXPECT_EQ(g.check(s + kBlock, kBlock, t += kPeriod), V::hold);
    EXPECT_EQ(g.check(s + 2 * kBlock, kBlock, t += kPeriod), back ? V::restart : V::jump) << "seed " << seed;
    for (int i = 3; i < 50; ++i) ASSERT_EQ(g.check(s + i * kBlock, kBlock, t += kPeriod), V::take);
  }
}

}  // namespace
}  // namespace hystloop
