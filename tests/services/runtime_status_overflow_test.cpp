// A report holds at most service_status_t::MAX_COUNTERS counters; one that has more does not lose
// them silently: its last counter becomes counters_dropped, how many did not fit. A report that
// fits is published as given.
#include <gtest/gtest.h>

#include <string>

#include <lcm/lcm-cpp.hpp>

#include "lcm/status_counters.hpp"
#include "runtime/status_reporter.hpp"

namespace hystloop {
namespace {

// "c<i>" (built with append: GCC 12's -Wrestrict misreads "c" + std::to_string(i) once inlined).
std::string name(int i) {
  std::string n = "c";
  n.append(std::to_string(i));
  return n;
}

TEST(RuntimeStatusOverflow, CountersBeyondTheBoundAreCountedInTheLastSlot) {
  lcm::LCM lcm("memq://");
  StatusReporter status(lcm, "HX_STATUS", "compensator");
  const int bound = service_status_t::MAX_COUNTERS;
  // The three the reporter adds itself (cpu_user_us, cpu_system_us, peak_rss_kB) fit exactly.
  for (int i = 0; i < bound - 3; ++i) status.counter(name(i), 1);
  ASSERT_TRUE(status.publish(1));
  EXPECT_EQ(status.status().n_counters, bound);
  EXPECT_FALSE(find_counter(status.status(), StatusReporter::kDroppedCounter).has_value());
  EXPECT_TRUE(find_counter(status.status(), "peak_rss_kB").has_value());

  // Ten more than fit (and an endpoint's whole set): the last slot counts them.
  status.begin(service_status_t::HEALTHY);
  for (int i = 0; i < bound + 7; ++i) status.counter(name(i), 1);
  EndpointCounters endpoint;
  status.endpoint("scan", endpoint);
  ASSERT_TRUE(status.publish(2));
  EXPECT_EQ(status.status().n_counters, bound);
  service_status_t whole{};
  add_endpoint_counters(whole, "scan", endpoint);
  // 7 + 3 counters past the bound, the endpoint's, and the slot given up to say so.
  EXPECT_EQ(find_counter(status.status(), StatusReporter::kDroppedCounter),
            std::optional<std::int64_t>(7 + 3 + whole.n_counters + 1));

  // A new report starts counting again.
  status.begin(service_status_t::HEALTHY);
  status.counter("only", 1);
  ASSERT_TRUE(status.publish(3));
  EXPECT_FALSE(find_counter(status.status(), StatusReporter::kDroppedCounter).has_value());
}

}  // namespace
}  // namespace hystloop
