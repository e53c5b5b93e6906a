// The bridge's HX_STATUS state and detail: a rig that clamps is DEGRADED, with the counts in the
// detail, beside the reasons the bridge already gave (late commands, dropped samples); SAFE and
// STOPPING say their own reason whatever else holds.
#include "bridge/bridge_health.hpp"

#include <gtest/gtest.h>

#include "hystloop/service_status_t.hpp"

namespace hystloop {
namespace {

BridgeHealthInput armed() {
  BridgeHealthInput in;
  in.armed = true;
  in.degraded_late_fraction = 0.01;
  return in;
}

TEST(BridgeHealth, ArmedAndNothingWrongIsHealthy) {
  const BridgeHealth h = assess_bridge_health(armed());
  EXPECT_EQ(h.state, service_status_t::HEALTHY);
  EXPECT_EQ(h.detail, "");
}

TEST(BridgeHealth, ClampedTicksInTheLastSecondAreDegraded) {
  BridgeHealthInput in = armed();
  in.clamped_last_second = {1234, 0, 1234};
  BridgeHealth h = assess_bridge_health(in);
  EXPECT_EQ(h.state, service_status_t::DEGRADED);
  EXPECT_EQ(h.detail, "1234 ticks clamped in the last second (range 0, slew 1234)");
  // A tick clamped by both counts once in the total, in each limit's own count.
  in.clamped_last_second = {1, 1, 1};
  h = assess_bridge_health(in);
  EXPECT_EQ(h.state, service_status_t::DEGRADED);
  EXPECT_EQ(h.detail, "1 ticks clamped in the last second (range 1, slew 1)");
}

TEST(BridgeHealth, EveryReasonIsSaid) {
  BridgeHealthInput in = armed();
  in.late_fraction = 0.05;
  in.samples_dropped = 3;
  in.clamped_last_second = {20, 20, 0};
  const BridgeHealth h = assess_bridge_health(in);
  EXPECT_EQ(h.state, service_status_t::DEGRADED);
  EXPECT_EQ(h.detail,
            "late fraction 5 % > 1 %; 3 samples dropped: the I/O thread fell behind; 20 ticks clamped in the last "
            "second (range 20, slew 0)");
  in.clamped_last_second = {};  // the reasons the bridge gave before are still there alone
  EXPECT_EQ(assess_bridge_health(in).detail, "late fraction 5 % > 1 %; 3 samples dropped: the I/O thread fell behind");
  in.late_fraction = 0.01;  // at the threshold is not above it
  in.samples_dropped = 0;
  EXPECT_EQ(assess_bridge_health(in).state, service_status_t::HEALTHY);
}

// Commands refused for ticks beyond bridge.max_lead_s: a horizon longer than the bridge takes, or
// a sensor stream that did not come from this bridge; either way not a healthy rig.
TEST(BridgeHealth, CommandsTooFarAheadOfTheClockAreDegraded) {
  BridgeHealthInput in = armed();
  in.commands_too_far_ahead = 40;
  in.max_lead_s = 0.06;
  const BridgeHealth h = assess_bridge_health(in);
  EXPECT_EQ(h.state, service_status_t::DEGRADED);
  EXPECT_NE(h.detail.find("40 commands refused for ticks more than 0.06 s ahead of the bridge's clock"),
            std::string::npos)
      << h.detail;
  EXPECT_NE(h.detail.find("bridge.max_lead_s"), std::string::npos) << h.detail;
}

TEST(BridgeHealth, SafeAndStoppingSayTheirOwnReason) {
  BridgeHealthInput in = armed();
  in.clamped_last_second = {5, 5, 0};
  in.armed = false;
  in.safe_reason = "disarmed via HX_CONTROL";
  BridgeHealth h = assess_bridge_health(in);
  EXPECT_EQ(h.state, service_status_t::SAFE);
  EXPECT_EQ(h.detail, "disarmed via HX_CONTROL");
  in.stopping = true;
  in.safe_u_V = 0.0;
  h = assess_bridge_health(in);
  EXPECT_EQ(h.state, service_status_t::STOPPING);
  EXPECT_EQ(h.detail, "stopping: ramping to the safe 0 V");
  in.at_safe_voltage = true;
  EXPECT_EQ(assess_bridge_health(in).detail, "stopping: at the safe 0 V");
}

// Repaired or unpublished samples make the bridge's status DEGRADED, saying so.
TEST(BridgeHealth, APeriodWithRepairedSamplesIsDegradedAndSaysWhy) {
  BridgeHealthInput in;
  in.armed = true;
  EXPECT_EQ(assess_bridge_health(in).state, service_status_t::HEALTHY);
  in.samples_repaired = 20;
  BridgeHealth h = assess_bridge_health(in);
  EXPECT_EQ(h.state, service_status_t::DEGRADED);
  EXPECT_NE(h.detail.find("20 samples held values no message may carry"), std::string::npos) << h.detail;
  in.samples_repaired = 0;
  in.samples_unpublished = 20;
  h = assess_bridge_health(in);
  EXPECT_EQ(h.state, service_status_t::DEGRADED);
  EXPECT_NE(h.detail.find("missing from the record"), std::string::npos) << h.detail;
}

}  // namespace
}  // namespace hystloop
