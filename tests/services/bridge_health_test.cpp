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

// A dry buffer names its cause as far as the bridge can tell: how long before the trip the last
// command block arrived, how many were refused and at what rate, a full real-time queue, and
// how long the I/O thread was held up.
TEST(BridgeHealth, TheWatchdogsReasonSaysWhyTheBufferRanDry) {
  DryBufferFigures f{.watchdog_s = 0.002,
                     .trip_tick = 1234,
                     .since_last_command_s = 0.0573,
                     .period_s = 0.5,
                     .commands_rejected = 60,
                     .command_queue_full = 0,
                     .io_longest_pass_s = 0.0004,
                     .io_longest_wait_s = 0.0201};
  const std::string why = watchdog_reason(f);
  EXPECT_NE(why.find("no command buffered for more than 0.002 s, tripped at tick 1234"), std::string::npos) << why;
  EXPECT_NE(why.find("the last command block arrived 57.3 ms before"), std::string::npos) << why;
  EXPECT_NE(why.find("60 HX_COMMAND message(s) refused in the last 0.5 s (120/s"), std::string::npos) << why;
  EXPECT_EQ(why.find("queue full"), std::string::npos) << why;
  EXPECT_NE(why.find("the I/O thread's longest pass 0.4 ms, longest wait 20.1 ms"), std::string::npos) << why;
  EXPECT_NE(why.find("re-arm via HX_CONTROL"), std::string::npos) << why;

  f.since_last_command_s = -1.0;
  f.command_queue_full = 7;
  f.axes = 2;
  f.tripped_by = 1;
  const std::string two = watchdog_reason(f);
  EXPECT_NE(two.find("on y, tripped at tick 1234"), std::string::npos) << two;
  EXPECT_NE(two.find("no command block received since the start"), std::string::npos) << two;
  EXPECT_NE(two.find("7 command ticks found the real-time queue full"), std::string::npos) << two;
  EXPECT_NE(two.find("every axis to the safe state"), std::string::npos) << two;

  f.command_after_trip = true;
  const std::string late = watchdog_reason(f);
  EXPECT_NE(late.find("command blocks kept arriving after it: too late for their ticks"), std::string::npos) << late;
}

// The hardware clock skipped ticks: the outputs held a stale voltage, whatever else is well.
TEST(BridgeHealth, SkippedTicksAreDegradedAndSayHowLong) {
  BridgeHealthInput in;
  in.armed = true;
  in.ticks_skipped = 50;
  in.dt_s = 1e-4;
  const BridgeHealth h = assess_bridge_health(in);
  EXPECT_EQ(h.state, service_status_t::DEGRADED);
  EXPECT_NE(h.detail.find("50 ticks (5 ms) skipped"), std::string::npos) << h.detail;
  in.ticks_skipped = 0;
  EXPECT_EQ(assess_bridge_health(in).state, service_status_t::HEALTHY);
  const std::string why = stall_reason(250, 0.01, 1e4, 81234);
  EXPECT_NE(why.find("250 ticks (25 ms) skipped within one second"), std::string::npos) << why;
  EXPECT_NE(why.find("bridge.max_stall_s 0.01 s"), std::string::npos) << why;
  EXPECT_NE(why.find("re-arm via HX_CONTROL"), std::string::npos) << why;
}

}  // namespace
}  // namespace hystloop
