// CounterSet: every service reports its counters since the last RESET_COUNTERS the same way.
#include "runtime/counter_set.hpp"

#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>

#include <optional>

#include "lcm/status_counters.hpp"

namespace hystloop {
namespace {

std::uint64_t value_of(const service_status_t& s, const std::string& name) {
  const std::optional<std::int64_t> value = find_counter(s, name);
  if (!value) ADD_FAILURE() << "no counter " << name;
  return static_cast<std::uint64_t>(value.value_or(0));
}

TEST(CounterSet, ReportsSinceTheLastRebaseForCountersAndEndpoints) {
  lcm::LCM lcm("memq://");
  StatusReporter status(lcm, "HX_STATUS", "test");
  CounterSet set;
  EndpointCounters endpoint;
  endpoint.received = 10;
  endpoint.accepted = 9;
  PublisherCounters publisher;
  publisher.published = 5;

  status.begin(1);
  set.report(status, {{"ticks", 100}, {"late", 3}});
  set.report(status, "command", endpoint);
  set.report(status, "sensor", publisher);
  EXPECT_EQ(value_of(status.status(), "ticks"), 100u);  // no reset yet: since start
  EXPECT_EQ(value_of(status.status(), "command.received"), 10u);

  set.rebase({{"ticks", 100}, {"late", 3}});
  set.rebase("command", endpoint);
  set.rebase("sensor", publisher);
  endpoint.received = 15;
  publisher.published = 7;
  status.begin(1);
  set.report(status, {{"ticks", 130}, {"late", 3}, {"new_counter", 2}});
  set.report(status, "command", endpoint);
  set.report(status, "sensor", publisher);
  EXPECT_EQ(value_of(status.status(), "ticks"), 30u);
  EXPECT_EQ(value_of(status.status(), "late"), 0u);
  EXPECT_EQ(value_of(status.status(), "new_counter"), 2u);  // unseen at the reset: from 0
  EXPECT_EQ(value_of(status.status(), "command.received"), 5u);
  EXPECT_EQ(value_of(status.status(), "sensor.published"), 2u);
  EXPECT_EQ(set.since("ticks", 130), 30u);
  // A counter that went back (its owner restarted) is reported as it is, never as a wrapped difference.
  EXPECT_EQ(set.since("ticks", 40), 40u);
}

}  // namespace
}  // namespace hystloop
