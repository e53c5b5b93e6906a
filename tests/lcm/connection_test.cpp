#include "lcm/connection.hpp"

#include <gtest/gtest.h>

#include <chrono>

#include "core/errors.hpp"
#include "lcm/message_fixtures.hpp"
#include "lcm/publisher.hpp"
#include "lcm/subscription.hpp"

namespace hystloop {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

TEST(Connection, OpenRefusesAnUnsafeUrlBeforeTouchingTheNetwork) {
  EXPECT_THROW(open_lcm("udpm://239.255.76.67:7667?ttl=1"), ParameterError);
  EXPECT_TRUE(open_lcm("memq://")->good());
}

TEST(Connection, HandlePendingTimesOutWithoutBlocking) {
  auto lcm = open_lcm("memq://");
  const auto start = Clock::now();
  EXPECT_EQ(handle_pending(*lcm, 20ms), 0);
  const auto waited = Clock::now() - start;
  EXPECT_GE(waited, 19ms);
  EXPECT_LT(waited, 500ms);
}

TEST(Connection, HandlePendingDispatchesUpToTheLimit) {
  auto lcm = open_lcm("memq://");
  Subscription<sensor_block_t> sub(*lcm, "HX_SENSOR");
  Publisher<sensor_block_t> pub(*lcm, "HX_SENSOR");
  for (std::int64_t k = 0; k < 10; ++k) pub.publish(fixtures::sensor_block(k));
  EXPECT_EQ(handle_pending(*lcm, 1s, 4), 4);
  EXPECT_EQ(handle_pending(*lcm, 0us), 6);
  EXPECT_EQ(handle_pending(*lcm, 0us), 0);
  EXPECT_EQ(sub.counters().accepted, 10u);
}

}  // namespace
}  // namespace hystloop
