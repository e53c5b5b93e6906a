#include "loop/command_buffer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <random>

#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

using Insert = CommandBuffer::Insert;
constexpr std::int64_t kCap = CommandBuffer::kCapacityTicks;

// A command whose value says which tick and which copy it is.
CommandTick command(std::int64_t seq, double copy = 0.0) {
  return {seq, static_cast<double>(seq) + copy, 1e-9 * static_cast<double>(seq), 3, 2};
}

// The buffer is 256 kB: keep it off the test's stack.
std::unique_ptr<CommandBuffer> make_buffer() { return std::make_unique<CommandBuffer>(); }

TEST(CommandBuffer, InOrderCommandsAreTakenAtTheirTicks) {
  auto b = make_buffer();
  EXPECT_EQ(b->next_tick(), 0);
  EXPECT_EQ(b->depth(), 0);
  for (std::int64_t s = 0; s < 10; ++s) {
    ASSERT_EQ(b->insert(command(s)), Insert::kStored);
    EXPECT_EQ(b->depth(), s + 1);
  }
  for (std::int64_t k = 0; k < 10; ++k) {
    const CommandTick* c = b->take(k);
    ASSERT_NE(c, nullptr) << k;
    EXPECT_EQ(c->seq, k);
    EXPECT_EQ(c->u_ff_V, static_cast<double>(k));
    EXPECT_EQ(c->params_version, 3);
    EXPECT_EQ(c->mode, 2);
    EXPECT_EQ(b->next_tick(), k + 1);
    EXPECT_EQ(b->depth(), 9 - k);
  }
  EXPECT_EQ(b->take(10), nullptr);  // ran dry: late
  EXPECT_EQ(b->depth(), 0);
}

TEST(CommandBuffer, OutOfOrderCommandsCountOnceTheGapFills) {
  auto b = make_buffer();
  EXPECT_EQ(b->insert(command(3)), Insert::kStored);
  EXPECT_EQ(b->depth(), 0);  // tick 0 missing: the next tick would be late
  EXPECT_EQ(b->insert(command(1)), Insert::kStored);
  EXPECT_EQ(b->insert(command(2)), Insert::kStored);
  EXPECT_EQ(b->depth(), 0);
  EXPECT_EQ(b->insert(command(0)), Insert::kStored);
  EXPECT_EQ(b->depth(), 4);
  EXPECT_EQ(b->insert(command(5)), Insert::kStored);
  EXPECT_EQ(b->depth(), 4);  // 4 missing
  EXPECT_EQ(b->insert(command(4)), Insert::kStored);
  EXPECT_EQ(b->depth(), 6);
  for (std::int64_t k = 0; k < 6; ++k) {
    const CommandTick* c = b->take(k);
    ASSERT_NE(c, nullptr);
    EXPECT_EQ(c->seq, k);
  }
}

TEST(CommandBuffer, ADuplicateLeavesTheFirstCommand) {
  auto b = make_buffer();
  ASSERT_EQ(b->insert(command(5, 0.25)), Insert::kStored);
  EXPECT_EQ(b->insert(command(5, 0.75)), Insert::kDuplicate);
  EXPECT_EQ(b->insert(command(5, 0.25)), Insert::kDuplicate);  // even an identical repeat
  b->take(4);
  const CommandTick* c = b->take(5);
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->u_ff_V, 5.25);
}

TEST(CommandBuffer, RefusesTicksBeyondItsCapacityAheadOfTheNextTick) {
  auto b = make_buffer();
  EXPECT_EQ(b->insert(command(kCap - 1)), Insert::kStored);
  EXPECT_EQ(b->insert(command(kCap)), Insert::kTooFarAhead);
  EXPECT_EQ(b->insert(command(kCap + 1000000)), Insert::kTooFarAhead);
  b->take(100);
  EXPECT_EQ(b->insert(command(100 + kCap)), Insert::kStored);  // = next_tick + kCap - 1
  EXPECT_EQ(b->insert(command(101 + kCap)), Insert::kTooFarAhead);
  // The one at kCap - 1 is still there, in the slot it shares with nothing live.
  for (std::int64_t k = 101; k < kCap - 1; ++k) EXPECT_EQ(b->take(k), nullptr);
  const CommandTick* c = b->take(kCap - 1);
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->seq, kCap - 1);
  c = b->take(100 + kCap);
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->seq, 100 + kCap);
}

TEST(CommandBuffer, RefusesTicksAlreadyTakenAsStale) {
  auto b = make_buffer();
  ASSERT_EQ(b->insert(command(10)), Insert::kStored);
  EXPECT_NE(b->take(10), nullptr);
  EXPECT_EQ(b->insert(command(10)), Insert::kStale);  // its tick has passed
  EXPECT_EQ(b->insert(command(3)), Insert::kStale);   // dropped unseen when tick 10 was taken
  EXPECT_EQ(b->insert(command(-1)), Insert::kStale);
  EXPECT_EQ(b->insert(command(11)), Insert::kStored);
  // take() does not go backwards: a tick before next_tick() gives nothing and changes nothing.
  EXPECT_EQ(b->take(5), nullptr);
  EXPECT_EQ(b->next_tick(), 11);
  EXPECT_EQ(b->depth(), 1);
  const CommandTick* c = b->take(11);
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->seq, 11);
  EXPECT_EQ(b->take(11), nullptr);  // nothing is given twice
}

// Kept full to the last slot for many laps of the ring: every tick comes out as it went in.
TEST(CommandBuffer, WrapsAroundItsRingManyTimes) {
  auto b = make_buffer();
  std::int64_t inserted_through = -1;
  constexpr std::int64_t kLaps = 12;
  for (std::int64_t k = 0; k < kLaps * kCap + 123; ++k) {
    while (inserted_through < b->next_tick() + kCap - 1) {
      ASSERT_EQ(b->insert(command(++inserted_through, 0.5)), Insert::kStored) << inserted_through;
    }
    ASSERT_EQ(b->depth(), kCap);
    ASSERT_EQ(b->insert(command(inserted_through + 1)), Insert::kTooFarAhead);
    const CommandTick* c = b->take(k);
    ASSERT_NE(c, nullptr) << k;
    ASSERT_EQ(c->seq, k);
    ASSERT_EQ(c->u_ff_V, static_cast<double>(k) + 0.5);
    ASSERT_EQ(b->depth(), kCap - 1);
  }
}

TEST(CommandBuffer, DepthAfterADrySpellAndSkippedTicks) {
  auto b = make_buffer();
  for (std::int64_t k = 0; k < 5; ++k) {
    EXPECT_EQ(b->take(k), nullptr);  // dry
    EXPECT_EQ(b->depth(), 0);
  }
  for (std::int64_t s = 10; s < 15; ++s) b->insert(command(s));
  EXPECT_EQ(b->depth(), 0);  // 5..9 still missing
  for (std::int64_t s = 5; s < 10; ++s) b->insert(command(s));
  EXPECT_EQ(b->depth(), 10);  // 5..14
  // Ticks 5..7 skipped (not taken): dropped, and the depth counts from 9.
  const CommandTick* c = b->take(8);
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->seq, 8);
  EXPECT_EQ(b->depth(), 6);
  EXPECT_EQ(b->insert(command(6)), Insert::kStale);
  // A skip beyond everything buffered: dry again, depth counts from the tick after.
  EXPECT_EQ(b->take(20), nullptr);
  EXPECT_EQ(b->next_tick(), 21);
  EXPECT_EQ(b->depth(), 0);
  for (std::int64_t s = 21; s < 26; ++s) b->insert(command(s));
  EXPECT_EQ(b->depth(), 5);
  b->insert(command(27));
  EXPECT_EQ(b->depth(), 5);
  b->insert(command(26));
  EXPECT_EQ(b->depth(), 7);
  // Skipping into the middle of a gap-free run keeps the rest.
  c = b->take(24);
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(b->depth(), 3);  // 25, 26, 27
  // A tick missing in the middle: the depth stops at the hole and resumes after it is taken.
  b->insert(command(29));
  b->insert(command(30));
  EXPECT_EQ(b->depth(), 3);
  for (std::int64_t k = 25; k < 28; ++k) ASSERT_NE(b->take(k), nullptr);
  EXPECT_EQ(b->depth(), 0);         // 28 missing
  EXPECT_EQ(b->take(28), nullptr);  // late
  EXPECT_EQ(b->depth(), 2);         // 29, 30
}

TEST(CommandBuffer, ClearDropsWhatIsBufferedAndKeepsWhatWasTaken) {
  auto b = make_buffer();
  for (std::int64_t s = 0; s < 100; ++s) b->insert(command(s));
  ASSERT_NE(b->take(0), nullptr);
  b->clear();
  EXPECT_EQ(b->next_tick(), 1);
  EXPECT_EQ(b->depth(), 0);
  EXPECT_EQ(b->take(1), nullptr);
  EXPECT_EQ(b->insert(command(1)), Insert::kStale);         // taken (late) already
  EXPECT_EQ(b->insert(command(50, 0.5)), Insert::kStored);  // not a duplicate: the old one is gone
  EXPECT_EQ(b->depth(), 0);
  for (std::int64_t s = 2; s < 50; ++s) b->insert(command(s));
  EXPECT_EQ(b->depth(), 49);
  for (std::int64_t k = 2; k < 50; ++k) ASSERT_NE(b->take(k), nullptr);
  const CommandTick* c = b->take(50);
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->u_ff_V, 50.5);
  EXPECT_EQ(b->take(51), nullptr);  // cleared
}

// What the buffer promises, written the obvious way: a map from tick to the first command.
class ReferenceBuffer {
 public:
  Insert insert(const CommandTick& c) {
    if (c.seq < next_) return Insert::kStale;
    if (c.seq >= next_ + kCap) return Insert::kTooFarAhead;
    return held_.emplace(c.seq, c).second ? Insert::kStored : Insert::kDuplicate;
  }
  std::optional<CommandTick> take(std::int64_t k) {
    if (k < next_) return std::nullopt;
    next_ = k + 1;
    std::optional<CommandTick> out;
    if (auto it = held_.find(k); it != held_.end()) out = it->second;
    held_.erase(held_.begin(), held_.upper_bound(k));
    return out;
  }
  std::int64_t depth() const {
    std::int64_t d = 0;
    for (auto it = held_.lower_bound(next_); it != held_.end() && it->first == next_ + d; ++it) ++d;
    return d;
  }
  void clear() { held_.clear(); }
  std::int64_t next_tick() const { return next_; }

 private:
  std::map<std::int64_t, CommandTick> held_;
  std::int64_t next_ = 0;
};

// Seeded random property: inserts near and far, repeated, stale, ahead of capacity, bursts that
// fill the whole ring; takes in order, skipping ticks, and backwards; clears. The buffer agrees
// with the map at every step.
TEST(CommandBuffer, AgreesWithAMapUnderRandomTraffic) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    std::mt19937_64 rng(seed);
    std::uniform_int_distribution<int> what(0, 9999);
    std::uniform_int_distribution<std::int64_t> near(-30, 400);
    std::uniform_int_distribution<std::int64_t> far(-kCap, 2 * kCap);
    std::uniform_int_distribution<std::int64_t> skip(0, 3);
    auto b = make_buffer();
    ReferenceBuffer ref;
    std::map<Insert, int> outcomes;  // the traffic must reach every case
    int taken = 0, late = 0, max_depth = 0;
    for (int step = 0; step < 100000; ++step) {
      const int w = what(rng);
      const double copy = static_cast<double>(step) * 1e-6;
      if (w < 6000) {
        const std::int64_t seq = ref.next_tick() + (w < 5500 ? near(rng) : far(rng));
        const Insert got = b->insert(command(seq, copy));
        ASSERT_EQ(got, ref.insert(command(seq, copy))) << "seed " << seed << " step " << step << " seq " << seq;
        ++outcomes[got];
      } else if (w < 9950) {
        // Mostly forward (sometimes skipping ticks), sometimes backwards.
        const std::int64_t k = w < 9900 ? ref.next_tick() + skip(rng) : ref.next_tick() - 1 - skip(rng);
        const CommandTick* got = b->take(k);
        const std::optional<CommandTick> want = ref.take(k);
        ASSERT_EQ(got != nullptr, want.has_value()) << "seed " << seed << " step " << step << " k " << k;
        ++(got != nullptr ? taken : late);
        if (got != nullptr) {
          ASSERT_EQ(got->seq, want->seq);
          ASSERT_EQ(got->u_ff_V, want->u_ff_V);  // the first copy
        }
      } else if (w < 9955) {
        // A whole horizon in order, up to and past the capacity.
        for (std::int64_t seq = ref.next_tick(); seq < ref.next_tick() + kCap + 2; ++seq) {
          ASSERT_EQ(b->insert(command(seq, copy)), ref.insert(command(seq, copy))) << "seed " << seed << " seq " << seq;
        }
      } else if (w < 9975) {
        b->clear();
        ref.clear();
      }
      ASSERT_EQ(b->next_tick(), ref.next_tick()) << "seed " << seed << " step " << step;
      if (step % 16 == 0) {
        ASSERT_EQ(b->depth(), ref.depth()) << "seed " << seed << " step " << step;
        max_depth = std::max(max_depth, static_cast<int>(b->depth()));
      }
    }
    for (Insert i : {Insert::kStored, Insert::kDuplicate, Insert::kStale, Insert::kTooFarAhead}) {
      EXPECT_GT(outcomes[i], 1000) << "seed " << seed << " outcome " << static_cast<int>(i);
    }
    EXPECT_GT(taken, 10000);
    EXPECT_GT(late, 1000);
    EXPECT_GT(max_depth, kCap - 10);
  }
}

TEST(CommandBuffer, AllocatesNothing) {
  auto b = make_buffer();
  std::mt19937_64 rng(9);
  std::uniform_int_distribution<std::int64_t> ahead(-5, 500);
  testing::AllocationCounter counter;
  std::int64_t taken = 0;
  for (std::int64_t k = 0; k < 3 * kCap; ++k) {
    for (int i = 0; i < 3; ++i) b->insert(command(k + ahead(rng)));
    if (b->take(k) != nullptr) ++taken;
    if (k % 5000 == 4999) b->clear();
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_GT(taken, 0);
}

}  // namespace
}  // namespace hystloop
