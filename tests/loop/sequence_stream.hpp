#pragma once
// A bridge's sensor stream as the compensator's SequenceGuard sees it (sequence_guard_test,
// sequence_discontinuities_test): blocks of kBlock ticks, one every kPeriod us, a guard whose step
// is the compensator's horizon.

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <initializer_list>

#include "loop/sequence_discontinuities.hpp"
#include "loop/sequence_guard.hpp"

namespace hystloop::testing {

using V = SequenceGuard::Verdict;
inline constexpr std::int64_t kStep = 500;        // ticks (the compensator's horizon)
inline constexpr std::int64_t kWindow = 100'000;  // us
inline constexpr std::int64_t kBlock = 20;        // ticks per block, one block every 2 ms
inline constexpr std::int64_t kPeriod = 2'000;    // us

// The guard and its clock; blocks go through `via` when a test sets it (SequenceDiscontinuities
// checks each with the guard), else straight to the guard.
struct GuardStream {
  SequenceGuard guard{kStep, kWindow};
  SequenceDiscontinuities* via = nullptr;
  std::int64_t t_us = 0;

  // The block starting at seq, kPeriod after the one before.
  V send(std::int64_t seq) {
    t_us += kPeriod;
    return via != nullptr ? via->check(guard, seq, kBlock, t_us) : guard.check(seq, kBlock, t_us);
  }
  // Blocks that continue a new numbering: each one held but the last, whose verdict is `confirmed`.
  void confirm(std::initializer_list<std::int64_t> seqs, V confirmed) {
    std::size_t i = 0;
    for (const std::int64_t seq : seqs) EXPECT_EQ(send(seq), ++i == seqs.size() ? confirmed : V::hold) << seq;
  }
  // A block `after_us` after the last one, the clock left where it was (a forged block between two
  // real ones).
  V send_between(std::int64_t seq, std::int64_t after_us) { return guard.check(seq, kBlock, t_us + after_us); }
  // All four of the guard's counters.
  void expect_counters(const SequenceGuard::Counters& want) const {
    const SequenceGuard::Counters& c = guard.counters();
    EXPECT_EQ(c.held, want.held) << "held";
    EXPECT_EQ(c.ignored, want.ignored) << "ignored";
    EXPECT_EQ(c.jumps, want.jumps) << "jumps";
    EXPECT_EQ(c.restarts, want.restarts) << "restarts";
  }
  // The blocks from `from` up to `to` (excluded), each one taken.
  void run(std::int64_t from, std::int64_t to) {
    for (std::int64_t s = from; s < to; s += kBlock) ASSERT_EQ(send(s), V::take) << s;
  }
};

}  // namespace hystloop::testing
