#include "lcm/status_counters.hpp"

#include <gtest/gtest.h>

#include "lcm/message_checks.hpp"
#include "lcm/message_fixtures.hpp"

namespace hystloop {
namespace {

TEST(StatusCounters, EndpointCountsBecomeNamedCountersAndTheRejectTotal) {
  auto status = fixtures::status(0);
  clear_counters(status);
  status.rejected = 0;
  EndpointCounters c;
  c.received = 10;
  c.accepted = 7;
  c.count(RejectReason::kNonFinite);
  c.count(RejectReason::kNonFinite);
  c.count(RejectReason::kSizeMismatch);
  ASSERT_TRUE(add_endpoint_counters(status, "command", c));
  ASSERT_EQ(status.n_counters, 2 + static_cast<int>(kRejectReasonCount));
  EXPECT_EQ(status.counter_names[0], "command.received");
  EXPECT_EQ(status.counter_values[0], 10);
  EXPECT_EQ(status.counter_names[1], "command.accepted");
  EXPECT_EQ(status.counter_names[2 + static_cast<int>(RejectReason::kNonFinite)], "command.rejected_non_finite");
  EXPECT_EQ(status.counter_values[2 + static_cast<int>(RejectReason::kNonFinite)], 2);
  EXPECT_EQ(status.rejected, 3);
  EXPECT_EQ(check_message(status), Verdict::kOk);

  PublisherCounters p;
  p.published = 5;
  ASSERT_TRUE(add_publisher_counters(status, "sensor", p));
  EXPECT_EQ(status.counter_names.back(), "sensor.transport_failed");
  EXPECT_EQ(check_message(status), Verdict::kOk);
}

TEST(StatusCounters, StopsAtTheContractsMaximumAndSaturates) {
  service_status_t status{};
  for (int i = 0; i < service_status_t::MAX_COUNTERS; ++i) ASSERT_TRUE(add_counter(status, "c", 1));
  EXPECT_FALSE(add_counter(status, "one too many", 1));
  EXPECT_EQ(status.n_counters, service_status_t::MAX_COUNTERS);
  clear_counters(status);
  add_counter(status, "huge", ~std::uint64_t{0});
  EXPECT_EQ(status.counter_values[0], std::numeric_limits<std::int64_t>::max());
}

}  // namespace
}  // namespace hystloop
