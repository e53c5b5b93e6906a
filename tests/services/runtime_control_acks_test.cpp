// ControlAcks: the answer a process gives to a control request, as it reaches HX_STATUS (the ids
// of the last request acted on and refused, a report owed at once, the reason for a while).
#include "runtime/control_acks.hpp"

#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>

#include <optional>
#include <string>

#include "lcm/status_counters.hpp"
#include "runtime/status_reporter.hpp"

namespace hystloop {
namespace {

std::optional<std::int64_t> counter(const service_status_t& s, const std::string& name) {
  return find_counter(s, name);
}

TEST(ControlAcks, TheIdsOfTheLastRequestsActedOnAndRefusedAreReportedAndAReportIsOwedAtOnce) {
  lcm::LCM lcm("memq://");
  StatusReporter status(lcm, "HX_STATUS", "bridge");
  ControlAcks acks;
  EXPECT_FALSE(acks.due());
  status.begin(service_status_t::HEALTHY);
  acks.report(status);
  EXPECT_EQ(counter(status.status(), "control_acted_request"), 0);  // present before any request
  EXPECT_EQ(counter(status.status(), "control_refused_request"), 0);

  acks.acted(41);
  EXPECT_TRUE(acks.due());
  acks.refused(42, "the bridge is stopping", 1'000'000);
  status.begin(service_status_t::HEALTHY);
  acks.report(status);
  EXPECT_FALSE(acks.due());  // reported
  EXPECT_EQ(counter(status.status(), "control_acted_request"), 41);
  EXPECT_EQ(counter(status.status(), "control_refused_request"), 42);
}

TEST(ControlAcks, TheReasonOfARefusalIsShownForAWhileThenNotAnyMore) {
  ControlAcks acks;
  EXPECT_EQ(acks.refusal_note(0), "");
  acks.refused(7, "reidentifier.models is off", 5'000'000);
  EXPECT_EQ(acks.refusal_note(5'000'000), "request 7 refused: reidentifier.models is off");
  EXPECT_EQ(acks.refusal_note(5'000'000 + ControlAcks::kReasonShownUs),
            "request 7 refused: reidentifier.models is off");
  EXPECT_EQ(acks.refusal_note(5'000'001 + ControlAcks::kReasonShownUs), "");
  acks.acted(8);  // acting on a later one leaves the last refusal as it was
  EXPECT_EQ(acks.last_refused(), 7);
  EXPECT_EQ(acks.last_acted(), 8);
}

}  // namespace
}  // namespace hystloop
