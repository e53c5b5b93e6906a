// SequenceDiscontinuities: a confirmed jump or restart is reported from the tick the old stream
// expected next to the first tick of the new numbering (not the last tick used before and the
// confirming block's), and a jump and a restart in one report period keep their own ticks.
#include "loop/sequence_discontinuities.hpp"

#include <gtest/gtest.h>

#include "sequence_stream.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

using testing::V;

// Every block through the discontinuities' check.
struct Stream : testing::GuardStream {
  Stream() { via = &d; }
  SequenceDiscontinuities d;
};

TEST(SequenceDiscontinuities, NothingBeforeADiscontinuityIsConfirmed) {
  Stream s;
  s.run(0, 1000);
  EXPECT_EQ(s.d.last_jump().expected_tick, -1);
  EXPECT_EQ(s.d.last_restart().resumed_tick, -1);
}

TEST(SequenceDiscontinuities, AJumpIsFromTheExpectedTickToTheNewNumberingsFirst) {
  Stream s;
  s.run(0, 1000);
  s.confirm({5000, 5020, 5040}, V::jump);
  EXPECT_EQ(s.d.last_jump().expected_tick, 1000);  // not 999, the last tick used
  EXPECT_EQ(s.d.last_jump().resumed_tick, 5000);   // not 5040, the confirming block's
  EXPECT_EQ(s.d.last_restart().expected_tick, -1);
}

TEST(SequenceDiscontinuities, ARestartIsFromTheExpectedTickToTheNewClocksFirst) {
  Stream s;
  s.run(50000, 51000);
  s.t_us += 3'000'000;                 // the bridge restarts: quiet, then its clock from 0
  s.confirm({0, 20, 60}, V::restart);  // one lost between: still consistent
  EXPECT_EQ(s.d.last_restart().expected_tick, 51000);
  EXPECT_EQ(s.d.last_restart().resumed_tick, 0);
}

// The candidate that is confirmed is the one that counts, not a forged block before it.
TEST(SequenceDiscontinuities, AnIgnoredCandidateDoesNotLendItsFirstTick) {
  Stream s;
  s.run(0, 1000);
  EXPECT_EQ(s.send(900'000), V::hold);     // forged, far ahead
  s.confirm({8000, 8020, 8040}, V::jump);  // far from both: a new candidate, the forged one ignored
  EXPECT_EQ(s.guard.counters().ignored, 1u);
  EXPECT_EQ(s.d.last_jump().expected_tick, 1000);
  EXPECT_EQ(s.d.last_jump().resumed_tick, 8000);
}

// Both in one report period (three forged blocks far ahead, then the real stream back): each
// line keeps its own ticks (they once both printed the restart's).
TEST(SequenceDiscontinuities, AJumpAndARestartKeepTheirOwnTicks) {
  Stream s;
  s.run(0, 1000);
  for (const std::int64_t seq : {5000, 5020, 5040}) s.send(seq);
  s.confirm({1000, 1020, 1040}, V::restart);
  EXPECT_EQ(s.d.last_jump().expected_tick, 1000);
  EXPECT_EQ(s.d.last_jump().resumed_tick, 5000);
  EXPECT_EQ(s.d.last_restart().expected_tick, 5060);
  EXPECT_EQ(s.d.last_restart().resumed_tick, 1000);
}

TEST(SequenceDiscontinuities, CheckingDoesNotAllocate) {
  Stream s;
  const hystloop::testing::AllocationCounter allocations;
  s.run(0, 1000);
  for (const std::int64_t seq : {5000, 5020, 5040}) s.send(seq);
  EXPECT_EQ(allocations.allocations(), 0u);
  EXPECT_EQ(s.d.last_jump().resumed_tick, 5000);
}

}  // namespace
}  // namespace hystloop
