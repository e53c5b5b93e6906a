// hystloop-bridge's configuration: defaults are the papers' and the issue's, every value is
// validated where it enters and a refusal names the field; the report handoff between the
// real-time and the I/O thread; the send-time ring behind the latency figures.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "bridge/bridge_settings.hpp"
#include "bridge/rt_report.hpp"
#include "bridge/send_time_ring.hpp"
#include "bridge/stage_backend.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

std::string refusal(const std::string& yaml) {
  try {
    load_bridge_settings(Config::from_string(yaml, "bridge.yaml"));
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(BridgeSettings, DefaultsAreTheIssues) {
  const BridgeSettings s = load_bridge_settings(Config());
  EXPECT_EQ(s.backend, "sim");
  EXPECT_EQ(s.rate_hz, 10000.0);
  EXPECT_EQ(s.stage.noise_rms_m, 1e-9);
  EXPECT_EQ(s.limits.u_min_V, -250.0);
  EXPECT_EQ(s.limits.u_max_V, 250.0);
  EXPECT_EQ(s.limits.watchdog_s, 2e-3);
  EXPECT_EQ(s.stage.banning.hysteresis.a, 8.58e-9);  // Table 1
  EXPECT_EQ(s.stage.banning.stage.k, 1.17e8);        // Table 2
  EXPECT_FALSE(s.auto_arm);
}

TEST(BridgeSettings, TheDeployConfigIsValidAndComplete) {
  const Config c = Config::load_file(std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/bridge.yaml");
  const BridgeSettings s = load_bridge_settings(c);
  EXPECT_EQ(s.limits.slew_V_per_s, 5e4);
  for (const std::string& key : bridge_config_keys()) EXPECT_TRUE(c.has(key)) << key << " is not documented";
}

TEST(BridgeSettings, RefusalsNameTheField) {
  EXPECT_NE(refusal("actuator: {watchdog_s: -1}").find("bridge.yaml: actuator.watchdog_s"), std::string::npos);
  EXPECT_NE(refusal("actuator: {u_min_V: 10, u_max_V: 5}").find("actuator.u_max_V"), std::string::npos);
  EXPECT_NE(refusal("actuator: {safe_u_V: 300}").find("actuator.safe_u_V"), std::string::npos);
  EXPECT_NE(refusal("actuator: {watchdog_s: 0.00015}").find("two ticks"), std::string::npos);
  EXPECT_NE(refusal("bridge: {backend: daq}").find("bridge.backend"), std::string::npos);
  EXPECT_NE(refusal("bridge: {noise_rms_m: .nan}").find("bridge.noise_rms_m"), std::string::npos);
  EXPECT_NE(refusal("banning: {hysteresis: {b: 9.0e-9}}").find("banning.hysteresis.b"), std::string::npos);
  EXPECT_NE(refusal("banning: {order: sideways}").find("banning.order"), std::string::npos);
  EXPECT_NE(refusal("ro: {c1: 0}").find("ro.c1"), std::string::npos);
  EXPECT_NE(refusal("rt: {priority: 50, io_priority: 50}").find("rt.io_priority"), std::string::npos);
  EXPECT_NE(refusal("actuator: {watchdog: 0.1}").find("did you mean 'actuator.watchdog_s'"), std::string::npos);
  EXPECT_EQ(refusal("bridge: {backend: ro, drift_fraction: 0.1}\nrt: {priority: 80, io_priority: 70}"), "accepted");
}

TEST(StageBackend, SimulatorsStepAndFlagThemselves) {
  BridgeSettings s;
  s.stage.noise_rms_m = 0.0;
  for (const char* name : {"sim", "ro"}) {
    auto backend = make_stage_backend(name, s.stage);
    EXPECT_EQ(backend->name(), name);
    StageReading r{};
    for (int k = 0; k < 2000; ++k) r = backend->step(100.0, k * 1e-4, 1e-4);
    EXPECT_GT(r.y_m, 3e-7) << name;  // ~0.6 um at 100 V
    EXPECT_LT(r.y_m, 1.2e-6) << name;
    EXPECT_EQ(r.flags, 4);           // SIMULATED
  }
  EXPECT_THROW(make_stage_backend("daq", s.stage), ParameterError);
}

TEST(RtReportExchange, HandsOverWithoutSharingABuffer) {
  RtReportExchange ex;
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> ticks{0};
  std::thread rt([&] {
    std::uint64_t k = 0;
    while (!stop.load()) {
      ex.current().work.add(static_cast<std::int64_t>(k % 100));
      ++k;
      ex.serve_request([&](RtReport& r) { r.core.ticks = k; });
      ticks.store(k);
    }
  });
  std::uint64_t seen_ticks = 0, seen_samples = 0;
  for (int round = 0; round < 50; ++round) {
    ex.request();
    const RtReport* r = nullptr;
    while ((r = ex.take()) == nullptr) std::this_thread::yield();
    EXPECT_GE(r->core.ticks, seen_ticks);  // cumulative counters only grow
    seen_samples += r->work.count();
    seen_ticks = r->core.ticks;
    ex.release();
    EXPECT_EQ(ex.take(), nullptr);
  }
  stop.store(true);
  rt.join();
  EXPECT_GT(seen_ticks, 0u);
  // Each window holds exactly the ticks since the previous report: none lost, none counted twice.
  EXPECT_EQ(seen_samples, seen_ticks);
}

TEST(SendTimeRing, MeasuresOnlySamplesItStillHolds) {
  SendTimeRing ring;
  testing::AllocationCounter counter;
  for (std::int64_t k = 0; k < 10000; ++k) ring.record(k, 1000 * k);
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(ring.elapsed_since(9999, 9999 * 1000 + 42).value(), 42);
  EXPECT_FALSE(ring.elapsed_since(10000 - static_cast<std::int64_t>(SendTimeRing::kSize) - 1, 0).has_value());
  EXPECT_FALSE(ring.elapsed_since(-1, 0).has_value());
  EXPECT_FALSE(ring.elapsed_since(20000, 0).has_value());
}

}  // namespace
}  // namespace hystloop
