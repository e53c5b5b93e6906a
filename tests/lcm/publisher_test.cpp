// Publisher<T>: refuses what the contract forbids before it leaves the process, and
// publishes blocks without allocating.
#include "lcm/publisher.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "lcm/connection.hpp"
#include "lcm/message_storage.hpp"
#include "lcm/message_fixtures.hpp"
#include "lcm/subscription.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

using namespace std::chrono_literals;

TEST(Publisher, RefusesInvalidMessagesAndCountsThem) {
  lcm::LCM lcm("memq://");
  Subscription<sensor_block_t> sub(lcm, "HX_SENSOR");
  Publisher<sensor_block_t> pub(lcm, "HX_SENSOR");
  auto bad = fixtures::sensor_block(1);
  bad.y_m.back() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(pub.publish(bad));
  EXPECT_TRUE(pub.publish(fixtures::sensor_block(2)));
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

  Publisher<sensor_block_t> sensor(lcm, "HX_SENSOR", nullptr);
  auto block = fixtures::sensor_block(5);
  block.flags.pop_back();  // one array a tick short
  EXPECT_FALSE(sensor.publish(block));
  Publisher<command_block_t> command(lcm, "HX_COMMAND", nullptr);
  auto plan = fixtures::command_block(5);
  plan.n_ticks += 1;
  EXPECT_FALSE(command.publish(plan));
  EXPECT_EQ(sensor.counters().encode_failed + command.counters().encode_failed, 2u);
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
// into a malloc'd queue entry; udpm sends from the caller's buffer). After one block of the
// largest size, blocks built in place with begin_block/append_tick go out without allocating.
TEST(Publisher, PublishingBlocksAllocatesNothingAfterWarmUp) {
  lcm::LCM lcm("memq://");
  Publisher<sensor_block_t> sensor(lcm, "HX_SENSOR");
  Publisher<command_block_t> command(lcm, "A_LONGER_RIG_PREFIX_COMMAND");
  auto s = fixtures::sensor_ticks(0, 10);
  auto c = fixtures::command_ticks(0, command_block_t::MAX_TICKS, 0);
  sensor.publish(s);
  command.publish(c);
  reserve_storage(s);
  reserve_storage(c);
  testing::AllocationCounter counter;
  for (std::int64_t k = 1; k <= 1000; ++k) {
    begin_block(s, 10 * k, fixtures::kBaseUtime + 1000 * k, 1e-4);
    for (std::int64_t t = 10 * k; t < 10 * k + 10; ++t) append_tick(s, fixtures::sensor_tick_values(t));
    begin_block(c, 10 * k + 200, fixtures::kBaseUtime + 1000 * k, 10 * k + 9);
    for (std::int64_t t = 10 * k + 200; t < 10 * k + 210; ++t) append_tick(c, fixtures::command_tick_values(t));
    sensor.publish(s);
    command.publish(c);
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(sensor.counters().published + command.counters().published, 2002u);
  handle_pending(lcm, 0us, 5000);  // empty the memq queue
}

}  // namespace
}  // namespace hystloop
