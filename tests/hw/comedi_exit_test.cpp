// The comedi backend under the bridge's real-time thread, against the fake card: the output is
// safe at start, and ramps (or steps, where the process is going down) to the safe voltage at
// every kind of exit: the stop a SIGINT/SIGTERM or SHUTDOWN begins, an exception unwinding the
// bridge, the watchdog, a sensor failing comedi.fault_limit times in a row, a fatal signal.
// Real threads, real time, a fast ramp: a few tenths of a second each.
#include "bridge/bridge_realtime.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <thread>
#include <vector>

#include "bridge/comedi_backend.hpp"
#include "fake_comedi.hpp"

namespace hystloop {
namespace {

using fake_comedi::kMaxdata;
constexpr double kGain = 25.0;

double written_V(const fake_comedi::Insn& insn) { return -10.0 + 20.0 * insn.data / double(kMaxdata); }

BridgeSettings comedi_settings() {
  BridgeSettings s;
  s.backend = "comedi";
  s.rt.ticks_per_wake = 1;
  s.block_ticks = 20;
  s.auto_arm = true;
  s.limits.safe_u_V = 0.0;
  s.limits.safe_ramp_V_per_s = 1e4;  // 1 V per tick at the piezo
  s.limits.watchdog_s = 1.0;
  s.stop_ramp_timeout_s = 2.0;
  // These exits are not the stall guard's (BridgeRealtimeStop tests it): on a busy machine the
  // fake card's thread may miss 10 ms in a second, which would go safe before what is tested.
  s.max_stall_s = 1.0;
  s.comedi.ao = {1, 0, 0, AREF_GROUND};
  s.comedi.ai = {0, 0, 0, AREF_GROUND};
  s.comedi.amplifier_gain_V_per_V = kGain;
  s.comedi.fault_limit = 10;
  return s;
}

// Started, armed by the first command and driven to `u_V`; the samples tell when it got there.
std::unique_ptr<BridgeRealtime> drive_to(const BridgeSettings& s, double u_V, std::int64_t ticks = 8000) {
  auto rt = std::make_unique<BridgeRealtime>(s, make_stage_backend(s));
  for (std::int64_t k = 0; k < ticks; ++k) EXPECT_TRUE(rt->push_command({k, u_V, std::nan(""), 1, 2}));
  rt->start();
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  bool there = false;
  while (!there && std::chrono::steady_clock::now() < until) {
    while (const auto t = rt->pop_tick()) there = there || t->tick().u_V == u_V;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_TRUE(there) << "the stage never got to " << u_V << " V";
  return rt;
}

// The output's writes (after the join): the first one safe, every step within the slew limit,
// those after the peak within the safe ramp (the card's code: one count of slack), the last safe.
void expect_safe_ramp(const BridgeSettings& s, double peak_V) {
  const auto& lists = fake_comedi::state().lists;
  std::vector<double> card_V;
  card_V.reserve(lists.size());
  for (const auto& l : lists) card_V.push_back(written_V(l.insns[0]));
  ASSERT_GE(card_V.size(), 3u);
  const double count_V = 20.0 / kMaxdata;
  EXPECT_NEAR(card_V.front(), s.limits.safe_u_V / kGain, count_V) << "not safe before arming";
  EXPECT_EQ(lists.front().n_insns, 1u);  // the start's write, before any tick
  bool past_peak = false;
  for (std::size_t i = 1; i < card_V.size(); ++i) {
    const double du = std::abs(card_V[i] - card_V[i - 1]) * kGain;
    ASSERT_LE(du, s.limits.slew_V_per_s * 1e-4 + kGain * count_V) << i;
    if (past_peak) {
      ASSERT_LE(du, s.limits.safe_ramp_V_per_s * 1e-4 + kGain * count_V) << i;
    }
    if (std::abs(card_V[i - 1] * kGain - peak_V) < kGain * count_V) past_peak = true;
  }
  EXPECT_TRUE(past_peak);
  EXPECT_NEAR(card_V.back(), s.limits.safe_u_V / kGain, count_V / 2);
}

class ComediExitTest : public ::testing::Test {
 protected:
  void SetUp() override { fake_comedi::reset(); }
};

TEST_F(ComediExitTest, TheStopOfASignalRampsToSafeThenHolds) {  // SIGINT/SIGTERM/SHUTDOWN: begin_safe_stop
  const BridgeSettings s = comedi_settings();
  auto rt = drive_to(s, 150.0);
  rt->begin_safe_stop();
  const SafeStopResult r = rt->stop();
  EXPECT_TRUE(r.reached);
  EXPECT_EQ(r.u_start_V, 150.0);
  EXPECT_EQ(r.ramp_ticks, 150);
  expect_safe_ramp(s, 150.0);
  EXPECT_EQ(fake_comedi::state().lists.back().n_insns, 1u);  // hold_safe's write came last
  rt.reset();
  EXPECT_EQ(fake_comedi::state().closes, 1);
}

TEST_F(ComediExitTest, AnExceptionUnwindingTheBridgeRampsToSafe) {
  const BridgeSettings s = comedi_settings();
  try {
    auto rt = drive_to(s, -120.0);
    throw std::runtime_error("something failed in the service");
  } catch (const std::runtime_error&) {
  }
  expect_safe_ramp(s, -120.0);
  EXPECT_EQ(fake_comedi::state().closes, 1);
}

TEST_F(ComediExitTest, TheWatchdogRampsToSafe) {
  BridgeSettings s = comedi_settings();
  s.limits.watchdog_s = 0.002;
  auto rt = drive_to(s, 100.0, 1000);  // 0.1 s of commands, then none: a trip 2 ms after the last
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  bool safe = false;
  while (!safe && std::chrono::steady_clock::now() < until) {
    while (const auto t = rt->pop_tick()) {
      safe =
          safe || ((t->tick().flags & sample_flags::kSafeState) != 0 && t->tick().u_V == 0.0 && t->tick().seq > 1000);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_TRUE(safe) << "the watchdog did not take it to the safe voltage";
  rt->stop();
  expect_safe_ramp(s, 100.0);
}

TEST_F(ComediExitTest, RepeatedSensorFaultsTakeTheBridgeToSafe) {
  const BridgeSettings s = comedi_settings();
  auto& reads = fake_comedi::state().reads;
  for (int i = 0; i < 600; ++i) reads.push_back({2, 40000});  // good reads (the stage holds still)
  for (int i = 0; i < 30; ++i) reads.push_back({1, 0});       // then the sensor's cable comes off
  auto rt = drive_to(s, 80.0);
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  int faults_before_safe = 0;
  bool safe = false;
  while (!safe && std::chrono::steady_clock::now() < until) {
    while (const auto t = rt->pop_tick()) {
      if (safe) continue;
      if ((t->tick().flags & sample_flags::kSafeState) != 0 && t->tick().seq > 100) {
        safe = true;
      } else if ((t->tick().flags & sample_flags::kSensorFault) != 0) {
        ++faults_before_safe;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_TRUE(safe) << "armed with commands buffered, yet never safe";
  EXPECT_EQ(faults_before_safe, s.comedi.fault_limit);  // disarmed at the tick after the limit was reached
  rt->stop();
  expect_safe_ramp(s, 80.0);
  const auto& c = dynamic_cast<const ComediBackend&>(rt->backend()).counters();
  EXPECT_EQ(c.sensor_faults.load(), 30u);
  EXPECT_EQ(c.fault_safe.load(), 1u);
}

TEST_F(ComediExitTest, AFatalSignalStepsTheOutputToSafe) {
  const BridgeSettings s = comedi_settings();
  EXPECT_DEATH(
      {
        ComediBackend b(s.comedi, s.limits);
        b.step(200.0, 0, 1e-4);
        std::abort();
      },
      "fatal signal: stepped the comedi output to the safe voltage");
  EXPECT_DEATH(
      {
        ComediBackend b(s.comedi, s.limits);
        std::terminate();
      },
      "std::terminate: stepped the comedi output to the safe voltage");
}

}  // namespace
}  // namespace hystloop
