#include "loop/spsc_queue.hpp"

#include <gtest/gtest.h>

#include <thread>

namespace hystloop {
namespace {

TEST(SpscQueue, FifoAndRefusesWhenFull) {
  SpscQueue<int, 4> q;
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(q.try_push(i));
  EXPECT_FALSE(q.try_push(99));
  for (int i = 0; i < 4; ++i) EXPECT_EQ(q.try_pop(), i);
  EXPECT_FALSE(q.try_pop().has_value());
}

TEST(SpscQueue, TwoThreadsLoseAndReorderNothing) {
  SpscQueue<long, 64> q;
  constexpr long kN = 200000;
  std::thread producer([&] {
    for (long i = 0; i < kN;) {
      if (q.try_push(i)) ++i;
    }
  });
  long expected = 0;
  while (expected < kN) {
    if (auto v = q.try_pop()) {
      ASSERT_EQ(*v, expected);
      ++expected;
    }
  }
  producer.join();
}

TEST(Mailbox, NewestWinsAndIsTakenOnce) {
  Mailbox<int> m;
  EXPECT_FALSE(m.take().has_value());
  m.post(1);
  m.post(2);
  m.post(3);
  EXPECT_EQ(m.take(), 3);
  EXPECT_FALSE(m.take().has_value());
  m.post(4);
  EXPECT_EQ(m.take(), 4);
}

TEST(Mailbox, ReaderNeverSeesATornOrOlderValue) {
  struct Pair {
    long a = 0, b = 0;
  };
  Mailbox<Pair> m;
  constexpr long kN = 200000;
  std::thread writer([&] {
    for (long i = 1; i <= kN; ++i) m.post(Pair{i, -i});
  });
  long last = 0;
  while (last < kN) {
    if (auto p = m.take()) {
      ASSERT_EQ(p->a, -p->b);
      ASSERT_GT(p->a, last);
      last = p->a;
    }
  }
  writer.join();
}

}  // namespace
}  // namespace hystloop
