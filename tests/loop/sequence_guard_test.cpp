// SequenceGuard: one forged (or corrupted) sensor block far ahead or behind is held and then
// ignored, the real blocks around it all taken; only kConfirmBlocks consecutive blocks that
// continue a new numbering, in quick succession, confirm a restart or a jump.
#include "loop/sequence_guard.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "sequence_stream.hpp"

namespace hystloop {
namespace {

using testing::GuardStream;
using testing::kBlock;
using testing::kPeriod;
using testing::kStep;
using testing::kWindow;
using testing::V;

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
  GuardStream s;
  s.run(1000, 2000);
  EXPECT_EQ(s.send_between(2000 + 900, 100), V::hold);  // forged
  s.run(2000, 3000);
  s.expect_counters({.held = 1, .ignored = 1});
}

TEST(SequenceGuard, OneBlock5000TicksBehindDoesNotRestart) {
  GuardStream s;
  s.run(50000, 51000);
  EXPECT_EQ(s.send_between(51000 - 5000, 100), V::hold);
  EXPECT_EQ(s.send_between(51000 - 5000 + kBlock, 200), V::hold);  // even two in a row
  s.run(51000, 52000);
  s.expect_counters({.held = 2, .ignored = 1});
}

TEST(SequenceGuard, ThreeConsecutiveBlocksConfirmARestart) {
  GuardStream s;
  s.run(50000, 51000);
  s.t_us += 3'000'000;                             // the bridge restarts: quiet, then its clock from 0
  s.confirm({0, kBlock, 3 * kBlock}, V::restart);  // one lost between: still consistent
  EXPECT_EQ(s.send(4 * kBlock), V::take);
  EXPECT_EQ(s.guard.next_expected(), 5 * kBlock);
  s.expect_counters({.held = 2, .restarts = 1});
}

TEST(SequenceGuard, ThreeConsecutiveBlocksConfirmAJumpAhead) {
  GuardStream s;
  s.run(0, 1000);
  s.confirm({10000, 10020, 10040}, V::jump);
  EXPECT_EQ(s.send(1000), V::hold);  // the old numbering is now the discontinuity
  EXPECT_EQ(s.send(10060), V::take);
  s.expect_counters({.held = 3, .ignored = 1, .jumps = 1});  // held: the two before the jump, the old numbering's
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
    GuardStream g;
    std::int64_t s = 200'000 + 50 * kBlock;
    g.run(200'000, s);
    if (rng() % 2 == 0) g.guard.check(s + 50'000, kBlock, g.t_us += 10);  // a forged one before
    const bool back = rng() % 2 == 0;
    s = back ? static_cast<std::int64_t>(rng() % 1000) : s + 20'000;
    SCOPED_TRACE(seed);
    g.confirm({s, s + kBlock, s + 2 * kBlock}, back ? V::restart : V::jump);
    for (int i = 3; i < 50; ++i) ASSERT_EQ(g.send(s + i * kBlock), V::take);
  }
}

}  // namespace
}  // namespace hystloop
