// HX_MODEL in hystloop-compensator: a set of any model goes through the admission path
// of HX_PARAMS (valid, newer per publisher over both channels, validated again), then the
// feedforward switches to that model at the next reversal; an unknown kind or format version is
// refused and counted by its reason, also when it arrives over the wire.
#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <string>

#include "compensator/compensator_service.hpp"
#include "lcm/blocks.hpp"
#include "lcm/connection.hpp"
#include "runtime/model_params_message.hpp"

namespace hystloop {
namespace {

constexpr std::int64_t kPublisher = 0x7e1d'0002;

CompensatorSettings cosine_settings() {
  CompensatorSettings s = load_compensator_settings(
      Config::load_file(std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/compensator.yaml"));
  s.control.horizon_ticks = 300;
  s.control.mode = FeedforwardMode::kMem;         // the MEM paper's workflow: a model change from MEM
  s.trajectory.shape = TrajectoryShape::kCosine;  // -1.6 um cos(2 pi t): a reversal near tick 510
  s.trajectory.amplitude_m = -1.6e-6;
  s.trajectory.blend_s = 0.05;
  return s;
}

model_params_t model_message(const ModelParamSet& set, std::int32_t version) {
  model_params_t m{};
  set_model(m, set);
  m.version = version;
  m.publisher_id = kPublisher;
  m.valid = true;
  m.source = "test";
  return m;
}

ModelParamSet pi15() {
  ModelParamSet set;
  set.kind = ModelKind::pi;
  set.pi = pi_params_from_mem(MemParams::paper_like(), 15, 250.0);
  return set;
}

struct Rig {
  std::unique_ptr<lcm::LCM> lcm = open_lcm("memq://");
  ChannelNames channels{};
  CompensatorService service{cosine_settings(), *lcm, channels};
  sensor_block_t block{};

  // Ticks [0, n) answered block by block (u = y = 0: only the plan matters here).
  void run(std::int64_t from, std::int64_t n) {
    for (std::int64_t k = from; k < from + n; k += 10) {
      begin_block(block, k, 1'700'000'000'000'000 + 100 * k, 1e-4);
      for (std::int64_t t = k; t < k + 10; ++t) append_tick(block, SensorTick{0, t, 0.0, 0.0, 0.0, 0.0, 0.0, 0});
      service.on_sensor(block, wall_utime());
    }
  }
};

TEST(CompensatorModel, APiSetSwitchesTheFeedforwardAtTheNextReversal) {
  Rig r;
  r.run(0, 20);
  ASSERT_EQ(r.service.compensator().mode(), FeedforwardMode::kMem);
  r.service.on_model(model_message(pi15(), 2));
  EXPECT_EQ(r.service.compensator().counters().params_accepted, 1u);
  EXPECT_EQ(r.service.compensator().mode(), FeedforwardMode::kMem);  // not before the reversal
  r.run(20, 1000);
  EXPECT_EQ(r.service.compensator().mode(), FeedforwardMode::kPi);
  EXPECT_EQ(r.service.compensator().params_version(), 2);
  EXPECT_EQ(r.service.compensator().counters().model_switches, 1u);
  EXPECT_EQ(r.service.compensator().model_params().pi.count, 15u);
}

TEST(CompensatorModel, RefusalsAreCountedByReason) {
  Rig r;
  r.run(0, 20);
  auto m = model_message(pi15(), 2);
  m.valid = false;
  r.service.on_model(m);
  EXPECT_EQ(r.service.counters().params_invalid, 1u);

  m = model_message(pi15(), 2);
  m.kind = 9;
  r.service.on_model(m);
  EXPECT_EQ(r.service.counters().model_unknown_kind, 1u);
  m = model_message(pi15(), 2);
  m.format_version = model_params_t::FORMAT_VERSION + 1;  // a later format
  r.service.on_model(m);
  EXPECT_EQ(r.service.counters().model_unknown_format, 1u);

  ModelParamSet bad = pi15();
  bad.pi.weights[1] = -2.0 * bad.pi.weights[0];  // a cumulative weight <= 0: not invertible
  r.service.on_model(model_message(bad, 3));
  EXPECT_EQ(r.service.counters().params_refused, 1u);

  r.service.on_model(model_message(pi15(), 4));
  EXPECT_EQ(r.service.compensator().counters().params_accepted, 1u);
  mem_params_t mem{};
  mem.version = 4;  // one version order per publisher over HX_PARAMS and HX_MODEL
  mem.publisher_id = kPublisher;
  mem.c1 = 5e-9;
  mem.c2 = 1e-12;
  mem.c3 = 1.2;
  mem.valid = true;
  r.service.on_params(mem);
  EXPECT_EQ(r.service.counters().params_stale, 1u);
  r.run(20, 1000);
  EXPECT_EQ(r.service.compensator().params_version(), 4);
}

TEST(CompensatorModel, AnUnknownKindOnTheWireReachesItsCounter) {
  Rig r;
  Publisher<model_params_t> pub(*r.lcm, r.channels.model, nullptr);  // unchecked: a newer sender
  auto m = model_message(pi15(), 2);
  m.kind = 7;
  ASSERT_TRUE(pub.publish(m));
  ASSERT_TRUE(pub.publish(model_message(pi15(), 3)));
  while (handle_pending(*r.lcm, std::chrono::microseconds(0), 100) > 0) {
  }
  EXPECT_EQ(r.service.counters().model_unknown_kind, 1u);
  EXPECT_EQ(r.service.compensator().counters().params_accepted, 1u);
}

}  // namespace
}  // namespace hystloop
