// Publisher<T>: refuses what the contract forbids before it leaves the process, and
// publishes fixed-size types without allocating.
#include "lcm/publisher.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "lcm/connection.hpp"
#include "lcm/message_fixtures.hpp"
#include "lcm/subscription.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

using namespace std::chrono_literals;

TEST(Publisher, RefusesInvalidMessagesAndCountsThem) {
  lcm::LCM lcm("memq://");
  Subscription<sensor_sample_t> sub(lcm, "HX_SENSOR");
  Publisher<sensor_sample_t> pub(lcm, "HX_SENSOR");
  auto bad = fixtures::sample(1);
  bad.y_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(pub.publish(bad));
  EXPECT_TRUE(pub.publish(fixtures::sample(2)));
  handle_pending(lcm, 0us);
  EXPECT_EQ(pub.counters().invalid, 1u);
  EXPECT_EQ(pub.counters().published, 1u);
  EXPECT_EQ(sub.counters().received, 1u);  // the NaN never went out
}

TEST(Publisher, RefusesArraysThatDisagreeWithTheirCountEvenUnchecked) {
  lcm::LCM lcm("memq://");
  Publisher<trajectory_t> pub(lcm, "HX_TRAJECTORY", nullptr);
  auto bad = fixtures::trajectory(3);
  bad.n_points += 10;  // encode would read past the vectors
  EXPECT_FALSE(pub.publish(bad));
  EXPECT_EQ(pub.counters().encode_failed, 1u);
}

TEST(Publisher, GrowsItsBufferForLargerVariableMessages) {
  lcm::LCM lcm("memq://");
  Subscription<service_status_t> sub(lcm, "HX_STATUS");
  Publisher<service_status_t> pub(lcm, "HX_STATUS");
  for (std::int64_t k = 0; k < 5; ++k) ASSERT_TRUE(pub.publish(fixtures::status(k)));
  handle_pending(lcm, 0us);
  EXPECT_EQ(sub.counters().accepted, 5u);
  EXPECT_EQ(fixtures::encode(sub.latest()), fixtures::encode(fixtures::status(4)));
}

// Counts operator new in this thread: the Publisher and lcm-cpp's raw publish. LCM's C
// core allocates with malloc, which this counter does not see (memq copies every message
// into a malloc'd queue entry; udpm sends from the caller's buffer).
TEST(Publisher, PublishingFixedSizeTypesAllocatesNothingAfterWarmUp) {
  lcm::LCM lcm("memq://");
  Publisher<sensor_sample_t> sensor(lcm, "HX_SENSOR");
  Publisher<actuator_command_t> command(lcm, "A_LONGER_RIG_PREFIX_COMMAND");
  auto s = fixtures::sample(0);
  auto c = fixtures::command(0);
  sensor.publish(s);
  command.publish(c);
  testing::AllocationCounter counter;
  for (std::int64_t k = 1; k <= 1000; ++k) {
    s.seq = k;
    c.seq = k;
    sensor.publish(s);
    command.publish(c);
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(sensor.counters().published + command.counters().published, 2002u);
  handle_pending(lcm, 0us, 5000);  // empty the memq queue
}

}  // namespace
}  // namespace hystloop
