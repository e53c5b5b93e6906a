// The comedi backend under the bridge's real-time thread, against the fake card: the output is
// safe at start, and ramps to the safe voltage at every kind of exit: the stop a SIGINT/SIGTERM or
// SHUTDOWN begins, an exception unwinding the bridge, the watchdog, a sensor failing
// comedi.fault_limit times in a row, a fatal signal. The amplifier enable line is active while
// armed and drops once the output is safe, on each of those paths; a heartbeat stops when the
// process is killed, which an external relay sees within its period. Real threads, real time, a
// fast ramp: a few tenths of a second each.
#include "bridge/bridge_realtime.hpp"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <functional>
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
// The DAC code of `card_V` in [-10, 10] V (comedi_from_phys).
lsampl_t code(double card_V) { return static_cast<lsampl_t>(std::floor((card_V + 10.0) / 20.0 * kMaxdata + 0.5)); }

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
  s.comedi.enable.channel = 3;  // the amplifier enable on digital line 3, a level
  return s;
}

constexpr unsigned kEnableBit = 1u << 3;

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
  for (const auto& l : lists) {
    if (l.insns[0].subdev == 1) card_V.push_back(written_V(l.insns[0]));  // not the enable's first write
  }
  ASSERT_GE(card_V.size(), 3u);
  const double count_V = 20.0 / kMaxdata;
  EXPECT_NEAR(card_V.front(), s.limits.safe_u_V / kGain, count_V) << "not safe before arming";
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

// The enable line in the card's record (its last kSharedEvents lists): active at some point, only
// ever inactive with the output at its safe code, inactive at the end.
void expect_enable_dropped_at_safe(const BridgeSettings& s) {
  const auto& rec = fake_comedi::shared();
  const std::uint64_t n = rec.events;
  ASSERT_GT(n, 0u);
  const lsampl_t safe = code(s.limits.safe_u_V / kGain);
  bool was_active = false;
  for (std::uint64_t i = n > fake_comedi::kSharedEvents ? n - fake_comedi::kSharedEvents : 0; i < n; ++i) {
    const fake_comedi::OutputEvent& e = rec.event(i);
    if (e.ao[0] == 0) continue;  // the enable's first write, before the output's
    if ((e.dio & kEnableBit) != 0) {
      was_active = true;
    } else {
      ASSERT_LE(std::abs(double(e.ao[0]) - double(safe)), 1.0) << "the enable was inactive away from safe, list " << i;
    }
  }
  EXPECT_TRUE(was_active) << "the enable never went active";
  EXPECT_EQ(rec.event(n - 1).dio & kEnableBit, 0u) << "the enable is still active";
}

// Runs `body` in a forked child (the card's record is shared with it); its wait status.
int in_child(const std::function<void()>& body, const std::function<void(pid_t)>& meanwhile = {}) {
  fake_comedi::shared();
  const pid_t pid = ::fork();
  if (pid == 0) {
    body();
    ::_exit(0);
  }
  if (meanwhile) meanwhile(pid);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return status;
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
  EXPECT_EQ(fake_comedi::state().lists.back().n_insns, 2u);  // hold_safe's write came last, the enable with it
  expect_enable_dropped_at_safe(s);
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
  expect_enable_dropped_at_safe(s);
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
  // The bridge runs on, disarmed: the enable dropped when the output got there.
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_EQ(fake_comedi::shared().dio.load() & kEnableBit, 0u);
  expect_enable_dropped_at_safe(s);
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

TEST_F(ComediExitTest, AFatalSignalRampsTheOutputToSafeThenDropsTheEnable) {
  const BridgeSettings s = comedi_settings();
  const auto& rec = fake_comedi::shared();
  std::uint64_t stepped = 0;
  const int status = in_child([&] {
    ComediBackend b(s.comedi, s.limits);
    b.set_output_enabled(true);
    b.step(150.0, 0, 1e-4);
    ::raise(SIGSEGV);
  });
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGSEGV) << status;
  for (std::uint64_t i = 0; i < rec.events; ++i) {
    if (rec.event(i).ao[0] == code(150.0 / kGain)) stepped = i;
  }
  ASSERT_GT(stepped, 0u);
  const std::uint64_t last = rec.events - 1;
  // 150 V at 1e4 V/s: 15 ms in 1 V steps (13 DAC counts) of 100 us each, then the safe list.
  EXPECT_GE(last - stepped, 151u);
  EXPECT_GE(rec.event(last - 1).t_ns - rec.event(stepped).t_ns, 149 * 100'000);
  for (std::uint64_t i = stepped + 1; i <= last; ++i) {
    const double du = std::abs(double(rec.event(i).ao[0]) - double(rec.event(i - 1).ao[0]));
    ASSERT_LE(du, 1.0 / kGain / 20.0 * kMaxdata + 1.0) << i;
    if (i < last) {
      EXPECT_NE(rec.event(i).dio & kEnableBit, 0u) << "the enable dropped before the output was safe";
    }
  }
  EXPECT_EQ(rec.event(last).ao[0], code(0.0));
  EXPECT_EQ(rec.event(last).dio & kEnableBit, 0u);
  EXPECT_DEATH(
      {
        ComediBackend b(s.comedi, s.limits);
        b.step(200.0, 0, 1e-4);
        std::abort();
      },
      "fatal signal: ramped the comedi outputs to the safe voltage, amplifier enable dropped");
  EXPECT_DEATH(
      {
        ComediBackend b(s.comedi, s.limits);
        std::terminate();
      },
      "std::terminate: ramped the comedi outputs to the safe voltage, amplifier enable dropped");
}

// A heartbeat beats while armed; SIGKILL ends it (nothing of the process runs), and the external
// relay (a retriggerable monostable of one heartbeat period, emulated here on the card's record)
// opens within that period.
TEST_F(ComediExitTest, AKilledBridgesHeartbeatStopsAndTheRelayOpensWithinItsPeriod) {
  BridgeSettings s = comedi_settings();
  s.comedi.enable.heartbeat = true;
  s.comedi.enable.heartbeat_hz = 500.0;
  const std::int64_t period_ns = 2'000'000;
  const auto& rec = fake_comedi::shared();
  const auto relay_closed = [&] {
    const std::int64_t edge = rec.last_dio_edge_ns;
    return edge > 0 && fake_comedi::monotonic_ns() - edge <= period_ns;
  };
  bool closed_while_running = false;
  std::int64_t killed_ns = 0;
  const int status = in_child(
      [&] {
        auto rt = drive_to(s, 100.0);  // 0.8 s of commands
        std::this_thread::sleep_for(std::chrono::seconds(20));
      },
      [&](pid_t pid) {
        const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
        while (!closed_while_running && std::chrono::steady_clock::now() < until) {
          // Beating: the line has changed within the period, and the output has left the safe voltage.
          closed_while_running = relay_closed() && rec.events > 200 && rec.event(rec.events - 1).ao[0] > 40000;
          std::this_thread::sleep_for(std::chrono::microseconds(200));
        }
        ::kill(pid, SIGKILL);
        killed_ns = fake_comedi::monotonic_ns();
      });
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << status;
  EXPECT_TRUE(closed_while_running) << "the heartbeat never held the relay";
  const std::int64_t wait_ns = killed_ns + period_ns - fake_comedi::monotonic_ns();
  if (wait_ns > 0) std::this_thread::sleep_for(std::chrono::nanoseconds(wait_ns));
  EXPECT_FALSE(relay_closed()) << "edges after SIGKILL";
  EXPECT_NE(rec.event(rec.events - 1).ao[0], code(0.0));  // nothing ramped: the relay's job
}

}  // namespace
}  // namespace hystloop
