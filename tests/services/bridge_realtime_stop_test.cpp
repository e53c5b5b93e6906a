// The bridge's stop on its real-time thread: every stop ramps the actuator to
// actuator.safe_u_V before the thread ends, also when nobody asked (the destructor while an
// exception unwinds), refuses to arm again once begun, tells the backend to hold_safe() after the
// ramp and at the end, and gives up after bridge's stop_ramp_timeout_s. Real threads, real time,
// a fast ramp: a few tenths of a second in all.
#include "bridge/bridge_realtime.hpp"
#include "bridge/bridge_health.hpp"
#include "support/eventually.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

namespace hystloop {
namespace {

constexpr double kDt = 1e-4;

// What the backend saw. Written on the real-time thread (step, the first hold_safe) and the
// test's thread (the later hold_safe calls, after the join); read after the join.
struct Record {
  std::vector<double> u_V;            // every step's voltage
  std::atomic<std::size_t> steps{0};  // how many steps so far, for the test's thread to wait on
  std::atomic<double> last_u_V{0.0};
  std::atomic<int> holds{0};
  std::size_t steps_at_first_hold = 0;
  double u_at_first_hold_V = std::nan("");
  double hold_arg_V = std::nan("");
};

class RecordingBackend final : public StageBackend {
 public:
  // simulated false: a hardware backend, whose missed deadlines are skipped. stall_at_step >= 0:
  // that step takes stall_ms (the bridge's own thread held up).
  explicit RecordingBackend(Record& r, bool simulated = true, std::size_t stall_at_step = SIZE_MAX, int stall_ms = 0)
      : r_(r), simulated_(simulated), stall_at_step_(stall_at_step), stall_ms_(stall_ms) {
    r_.u_V.reserve(1 << 20);
  }
  StageReading step(double u_V, double, double) noexcept override {
    if (r_.steps.load() == stall_at_step_) std::this_thread::sleep_for(std::chrono::milliseconds(stall_ms_));
    if (r_.u_V.size() < r_.u_V.capacity()) r_.u_V.push_back(u_V);
    r_.last_u_V.store(u_V);
    r_.steps.fetch_add(1);
    return {u_V * y_per_V, 4};
  }
  const std::string& name() const noexcept override { return name_; }
  bool simulated() const noexcept override { return simulated_; }  // true: ticks run late, never skipped
  double y_per_V = 0.0;                                            // the position it reports [m/V]

  void hold_safe(std::span<const double> safe_u_V) noexcept override {
    if (r_.holds.fetch_add(1) == 0) {
      r_.steps_at_first_hold = r_.u_V.size();
      r_.u_at_first_hold_V = r_.u_V.empty() ? std::nan("") : r_.u_V.back();
    }
    r_.hold_arg_V = safe_u_V[0];
  }

 private:
  Record& r_;
  bool simulated_;
  std::size_t stall_at_step_;
  int stall_ms_;
  std::string name_ = "recording";
};

BridgeSettings fast_ramp_settings() {
  BridgeSettings s;
  s.rt.ticks_per_wake = 20;
  s.block_ticks = 20;
  s.auto_arm = true;
  s.limits.safe_u_V = 0.0;
  s.limits.safe_ramp_V_per_s = 1e4;  // 1 V per tick: 200 V in 200 ticks (20 ms)
  s.limits.watchdog_s = 1.0;         // the commands below last 0.8 s: no trip in these tests
  s.stop_ramp_timeout_s = 2.0;
  return s;
}

using testing::eventually;

// The real-time thread's next report, copied: requested, waited for and released.
std::optional<RtReport> next_report(BridgeRealtime& rt) {
  rt.reports().request();
  const RtReport* report = nullptr;
  if (!eventually([&] { return (report = rt.reports().take()) != nullptr; })) return std::nullopt;
  const RtReport copy = *report;
  rt.reports().release();
  return copy;
}

// Started, armed by the first command and driven to `u_V` (the slew limit: 5 V per tick).
std::unique_ptr<BridgeRealtime> drive_to(const BridgeSettings& s, Record& record, double u_V) {
  auto rt = std::make_unique<BridgeRealtime>(s, std::make_unique<RecordingBackend>(record));
  for (std::int64_t k = 0; k < 8000; ++k) EXPECT_TRUE(rt->push_command({k, u_V, std::nan(""), 1, 2}));
  rt->start();
  EXPECT_TRUE(eventually([&] { return record.last_u_V.load() == u_V; })) << "the stage never got there";
  return rt;
}

// Every step within the slew limit, those after the peak within the ramp; the last at safe.
void expect_safe_ramp(const Record& r, const BridgeSettings& s, double peak_V) {
  ASSERT_FALSE(r.u_V.empty());
  bool past_peak = false;
  for (std::size_t i = 1; i < r.u_V.size(); ++i) {
    const double du = std::abs(r.u_V[i] - r.u_V[i - 1]);
    ASSERT_LE(du, s.limits.slew_V_per_s * kDt * (1 + 1e-12)) << "tick " << i;
    if (past_peak) {
      ASSERT_LE(du, s.limits.safe_ramp_V_per_s * kDt * (1 + 1e-12)) << "tick " << i;
    }
    if (r.u_V[i - 1] == peak_V) past_peak = true;
  }
  EXPECT_TRUE(past_peak);
  EXPECT_EQ(r.u_V.back(), s.limits.safe_u_V);
  EXPECT_EQ(r.u_at_first_hold_V, s.limits.safe_u_V);  // hold_safe came after the ramp
  EXPECT_EQ(r.hold_arg_V, s.limits.safe_u_V);
}

TEST(BridgeRealtimeStop, DestroyedWhileArmedRampsToSafeFirst) {  // an exception unwinding the service
  const BridgeSettings s = fast_ramp_settings();
  Record record;
  auto rt = drive_to(s, record, 200.0);
  rt.reset();
  expect_safe_ramp(record, s, 200.0);
  EXPECT_GE(record.holds.load(), 2);  // after the ramp (real-time thread) and at the end
}

TEST(BridgeRealtimeStop, StopRampsRefusesToArmAndReportsTheRamp) {
  const BridgeSettings s = fast_ramp_settings();
  Record record;
  auto rt = drive_to(s, record, -200.0);
  rt->begin_safe_stop();
  ASSERT_TRUE(eventually([&] { return rt->safe_reached(); })) << "the ramp never reached the safe voltage";
  // A late ARM: refused, the commands keep coming. Each tick takes the pending request before it
  // steps, so the second step counted after the request comes from a tick that saw it; two wakes
  // of ticks later, an ARM taken would have moved u (5 V a tick).
  rt->request_arm(ArmRequest::kArm);
  const std::size_t steps_at_arm = record.steps.load();
  ASSERT_TRUE(eventually([&] {
    return record.steps.load() >= steps_at_arm + 2 * static_cast<std::size_t>(s.rt.ticks_per_wake);
  })) << "the real-time thread stopped stepping after the late ARM";
  const SafeStopResult r = rt->stop();
  EXPECT_TRUE(r.requested);
  EXPECT_TRUE(r.reached);
  EXPECT_EQ(r.u_start_V, -200.0);
  EXPECT_EQ(r.ramp_ticks, 200);
  EXPECT_NEAR(r.ramp_s, 0.02, 1e-12);
  EXPECT_GT(r.wall_s, 0.0);
  EXPECT_LT(r.wall_s, s.stop_ramp_timeout_s);
  expect_safe_ramp(record, s, -200.0);
  // Nothing moved after the safe voltage was first applied.
  for (std::size_t i = record.steps_at_first_hold; i < record.u_V.size(); ++i) ASSERT_EQ(record.u_V[i], 0.0) << i;
  EXPECT_EQ(rt->stop().ramp_ticks, 200);  // idempotent
}

TEST(BridgeRealtimeStop, GivesUpAfterTheTimeoutAndStillHoldsSafe) {
  BridgeSettings s = fast_ramp_settings();
  s.limits.safe_ramp_V_per_s = 10.0;  // 20 s for 200 V
  s.stop_ramp_timeout_s = 0.05;       // not a valid configuration (load_bridge_settings refuses it)
  Record record;
  auto rt = drive_to(s, record, 200.0);
  const auto t0 = std::chrono::steady_clock::now();
  rt->begin_safe_stop();
  // Given up while ramping: a thread starved by a busy machine may not step within the 50 ms, so
  // the stop is waited for once the ramp has begun, not at a fixed time.
  ASSERT_TRUE(eventually([&] { return record.last_u_V.load() < 200.0; })) << "the ramp never began";
  const SafeStopResult r = rt->stop();
  const double waited_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_TRUE(r.requested);
  EXPECT_FALSE(r.reached);
  EXPECT_GE(waited_s, 0.05);
  EXPECT_LT(waited_s, 10.0);  // gave up: the whole ramp takes 20 s
  EXPECT_GE(r.wall_s, 0.05);
  EXPECT_GT(r.ramp_ticks, 0);
  EXPECT_LT(record.u_V.back(), 200.0);  // it was ramping
  EXPECT_EQ(record.holds.load(), 1);    // told to hold safe at the end anyway
  EXPECT_EQ(record.hold_arg_V, 0.0);
}

// A hardware backend whose bridge thread is held up for longer than bridge.max_stall_s: the
// outputs held a stale voltage, so every axis ramps to the safe voltage from the tick after the
// stall, counted and reported (the service names the reason: stall_reason).
TEST(BridgeRealtimeStop, AStallOfItsOwnClockBeyondTheBoundRampsToSafe) {
  BridgeSettings s = fast_ramp_settings();
  s.rt.ticks_per_wake = 1;
  s.max_stall_s = 0.01;  // 100 ticks; the stall below is 40 ms, 400 at least
  Record record;
  auto rt = std::make_unique<BridgeRealtime>(s, std::make_unique<RecordingBackend>(record, false, 3000, 40));
  for (std::int64_t k = 0; k < 16000; ++k) ASSERT_TRUE(rt->push_command({k, 200.0, std::nan(""), 1, 2}));
  rt->start();
  ASSERT_TRUE(eventually([&] { return record.steps.load() > 3000 && record.last_u_V.load() == 0.0; }))
      << "the stage did not go back to the safe voltage after the stall";
  const std::optional<RtReport> report = next_report(*rt);
  ASSERT_TRUE(report) << "no report from the real-time thread";
  EXPECT_EQ(report->stall_trips, 1u);
  EXPECT_GE(report->ticks_skipped, 300u);
  EXPECT_GT(report->last_stall_ticks, 100u);  // beyond the bound (a busy machine may trip it earlier)
  EXPECT_FALSE(report->armed);
  EXPECT_EQ(report->core.watchdog_trips, 0u);  // commands were there: the stall, not the compensator
  rt->stop();
  // Up at the slew limit (to 200 V, unless a busy machine stalled the thread earlier), then down
  // at the safe ramp (1 V a tick), never a step.
  double peak = 0.0;
  for (const double u : record.u_V) peak = std::max(peak, u);
  expect_safe_ramp(record, s, peak);
}

// A stall within the bound is skipped and counted, and the rig stays armed (DEGRADED on HX_STATUS:
// bridge_health_test).
TEST(BridgeRealtimeStop, AShortStallOfItsOwnClockIsCountedAndStaysArmed) {
  BridgeSettings s = fast_ramp_settings();
  s.rt.ticks_per_wake = 1;
  s.max_stall_s = 1.0;  // the bound's upper end: a 20 ms stall is within it on any machine
  Record record;
  auto rt = std::make_unique<BridgeRealtime>(s, std::make_unique<RecordingBackend>(record, false, 3000, 20));
  for (std::int64_t k = 0; k < 16000; ++k) ASSERT_TRUE(rt->push_command({k, 200.0, std::nan(""), 1, 2}));
  rt->start();
  ASSERT_TRUE(eventually([&] { return record.steps.load() > 3500; }));
  const std::optional<RtReport> report = next_report(*rt);
  ASSERT_TRUE(report) << "no report from the real-time thread";
  EXPECT_EQ(report->stall_trips, 0u);
  EXPECT_GE(report->ticks_skipped, 150u);
  EXPECT_TRUE(report->armed);
  EXPECT_EQ(record.last_u_V.load(), 200.0);
}

// A soft position limit: the stage (1 um per 100 V here) driven towards 2 um with a limit at 1 um
// goes to the safe state three ticks beyond it, ramped, and says so.
TEST(BridgeRealtimeStop, APositionBeyondItsSoftLimitRampsToSafe) {
  BridgeSettings s = fast_ramp_settings();
  s.limits.position_max_m = 1e-6;
  Record record;
  auto backend = std::make_unique<RecordingBackend>(record);
  backend->y_per_V = 1e-8;
  auto rt = std::make_unique<BridgeRealtime>(s, std::move(backend));
  for (std::int64_t k = 0; k < 8000; ++k) ASSERT_TRUE(rt->push_command({k, 200.0, std::nan(""), 1, 2}));
  rt->start();
  ASSERT_TRUE(eventually([&] { return record.steps.load() > 400; }));
  const std::optional<RtReport> report = next_report(*rt);
  ASSERT_TRUE(report) << "no report from the real-time thread";
  EXPECT_EQ(report->position_trips, 1u);
  EXPECT_EQ(report->position_axis, 0);
  EXPECT_GT(report->position_m, 1e-6);
  EXPECT_FALSE(report->armed);
  rt->stop();
  // Up at the slew limit (5 V a tick) past 100 V for the three ticks and the one the disarm
  // takes effect after, then down at the safe ramp (1 V a tick) to 0 V.
  double peak = 0.0;
  for (const double u : record.u_V) peak = std::max(peak, u);
  EXPECT_GT(peak, 100.0);
  EXPECT_LE(peak, 125.0);
  expect_safe_ramp(record, s, peak);
  EXPECT_NE(position_reason(0, 1.2e-6, s.limits, 1, 25)
                .find("x's measured position 1.2 um beyond "
                      "actuator.position_max_m 1 um for 3 ticks"),
            std::string::npos);
}

// A servo whose loop is unstable on the stage (kp 1.5 on a stage of the nominal gain with the
// tick between a voltage and its sample: a closed-loop pole at -1.5) rings at half the tick rate
// and grows; the detector finds it within its hold and every axis ramps to safe, the frequency named.
TEST(BridgeRealtimeStop, AnOscillatingServoRampsToSafeNamingTheFrequency) {
  BridgeSettings s = fast_ramp_settings();
  s.servo.kp = 1.5;
  s.servo.ki = 0.0;
  Record record;
  auto backend = std::make_unique<RecordingBackend>(record);
  backend->y_per_V = s.servo.nominal_gain_m_per_V;
  auto rt = std::make_unique<BridgeRealtime>(s, std::move(backend));
  // 0.5 V off the feedforward's own position: the error the loop amplifies, 1.5 times a tick,
  // until the slew limit (5 V a tick) bounds it: the servo's output then swings about +-3.75 V.
  const double y_ref_m = 10.5 * s.servo.nominal_gain_m_per_V;
  for (std::int64_t k = 0; k < 8000; ++k) ASSERT_TRUE(rt->push_command({k, 10.0, y_ref_m, 1, 2}));
  rt->start();
  std::optional<RtReport> report;
  ASSERT_TRUE(eventually([&] { return (report = next_report(*rt)) && report->oscillation_trips > 0; }))
      << "the oscillation was not found";
  EXPECT_EQ(report->oscillation_trips, 1u);
  EXPECT_EQ(report->oscillation_axis, 0);
  EXPECT_NEAR(report->oscillation_hz, 5000.0, 250.0);
  EXPECT_GT(report->oscillation_rms_V, s.oscillation.rms_V);
  EXPECT_FALSE(report->armed);
  ASSERT_TRUE(eventually([&] { return record.last_u_V.load() == s.limits.safe_u_V; }));
  rt->stop();
  // Armed at the first tick: beyond the bound for the hold (200 ticks) after the mean square's rise.
  const std::int64_t trip = report->oscillation_tick;
  EXPECT_GE(trip, 200);
  EXPECT_LE(trip, 600);
  // From the tick after the one the disarm takes effect at: down at the safe ramp (1 V a tick).
  ASSERT_GT(record.u_V.size(), static_cast<std::size_t>(trip) + 3);
  for (std::size_t i = static_cast<std::size_t>(trip) + 3; i < record.u_V.size(); ++i) {
    ASSERT_LE(std::abs(record.u_V[i] - record.u_V[i - 1]), s.limits.safe_ramp_V_per_s * kDt * (1 + 1e-12))
        << "step " << i;
  }
  EXPECT_EQ(record.u_V.back(), s.limits.safe_u_V);
  EXPECT_NE(oscillation_reason(0, 5000.0, 7.1, s.oscillation, 1, 4567)
                .find("x's servo oscillates at 5000 Hz: its output 7.1 V RMS above 300 Hz for 20 ms, beyond "
                      "bridge.oscillation_rms_V 1 V: the actuator to the safe state at tick 4567"),
            std::string::npos);
}

}  // namespace
}  // namespace hystloop
