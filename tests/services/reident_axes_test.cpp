// The re-identifier on a stage of several axes, one process per axis: a core fits its own axis
// of every sensor block (x and y driven through different MEM sets: each finds its own), refuses
// a block without its axis, reads the applied version from its axis's command ticks and numbers
// its sets above that alone, and leaves sets for another axis on HX_PARAMS alone (not adopted,
// not followed, never forged). The service is named after its axis ("reidentifier" for x, as
// before axes existed), acts on control requests for that name, and its sets carry its axis.
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <array>
#include <chrono>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/clock.hpp"
#include "core/errors.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/model_params_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/connection.hpp"
#include "lcm/subscription.hpp"
#include "reident/reident_core.hpp"
#include "reidentifier/reident_service.hpp"
#include "services/reident_test_data.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

using testdata::gain_scaled;
using testdata::rel_err;
using testdata::sample_tick;
using Kind = RefitDecision::Kind;

constexpr std::int64_t kSecond = 1'000'000;  // us
constexpr std::size_t kBlockTicks = 10;
constexpr std::int64_t kOtherPublisher = 0x1de;

// One XY stage: each axis its own drive and its own MEM set (gains 1.1 and 0.85 of the set the
// cores start from: a fit of the wrong axis is 20 % off), 1 nm of sensor noise.
struct XyRecord {
  MemParams initial = testdata::piezo_truth();
  MemParams truth_x = gain_scaled(initial, 1.1);
  MemParams truth_y = gain_scaled(initial, 0.85);
  testdata::SineRecord x, y;

  explicit XyRecord(double duration_s) {
    x.u = testdata::sine_input(250.0, 10.0, 1e4, duration_s);
    x.y = testdata::mem_branches(x.u, truth_x);
    testdata::add_noise(x.y, 1e-9, 21);
    y.u = testdata::sine_input(200.0, 8.0, 1e4, duration_s);
    y.y = testdata::mem_branches(y.u, truth_y);
    testdata::add_noise(y.y, 1e-9, 22);
  }
};

ReidentOptions options_for(int axis, const MemParams& initial) {
  ReidentOptions o = testdata::small_reident_options(initial);
  o.axis = axis;
  return o;
}

// Ticks seq .. seq + n - 1 of both axes, from index `from` of the record, tick-major as the bridge sends them.
void fill_xy_block(sensor_block_t& b, std::int64_t seq, std::int64_t utime, const XyRecord& r, std::size_t from,
                   std::size_t n) {
  begin_block(b, seq, utime, testdata::kTickPeriod_s, 2);
  for (std::size_t k = from; k < from + n; ++k) {
    const std::array<SensorTick, 2> ticks{sample_tick(r.x.u[k], r.x.y[k]), sample_tick(r.y.u[k], r.y.y[k])};
    append_tick(b, ticks);
  }
}

// Commands of both axes for ticks seq .. seq + n - 1, from parameter versions x_version and y_version.
void fill_xy_commands(command_block_t& b, std::int64_t seq, std::int64_t n, std::int32_t x_version,
                      std::int32_t y_version) {
  begin_block(b, seq, 0, seq - 1, 2);
  for (std::int64_t k = seq; k < seq + n; ++k) {
    const std::array<CommandTick, 2> ticks{CommandTick{.seq = k, .params_version = x_version},
                                           CommandTick{.seq = k, .params_version = y_version}};
    append_tick(b, ticks);
  }
}

// The same two-axis blocks to every sink, 10 kHz of fake time.
struct XyStream {
  XyRecord record{2.0};
  sensor_block_t block = testdata::reserved_sensor_block();
  std::int64_t seq = 0;
  std::int64_t now = 10 * kSecond;  // fake clock [us]
  std::size_t position = 0;

  void send(double seconds, const std::vector<std::function<void(const sensor_block_t&, std::int64_t)>>& sinks) {
    const auto n = static_cast<std::size_t>(std::llround(seconds * 1e4));
    for (std::size_t k = 0; k < n; k += kBlockTicks) {
      fill_xy_block(block, seq, now, record, position + k, kBlockTicks);
      for (const auto& sink : sinks) sink(block, now);
      seq += static_cast<std::int64_t>(kBlockTicks);
      now += static_cast<std::int64_t>(kBlockTicks) * testdata::kTickPeriod_us;
    }
    position += n;
  }
  std::function<void(const sensor_block_t&, std::int64_t)> into(ReidentCore& core) {
    return [&core](const sensor_block_t& b, std::int64_t now_us) { core.on_sensor_block(b, now_us); };
  }
};

// poll; if that started a job, run it and poll again for the decision.
RefitDecision refit(ReidentCore& core, std::int64_t now) {
  RefitDecision d = core.poll(now);
  if (core.worker().run_pending()) d = core.poll(now);
  return d;
}

TEST(ReidentAxes, EachCoreFitsItsOwnAxisOfTheSameBlocks) {
  XyStream s;
  ReidentCore x{options_for(0, s.record.initial), "reident@test", /*start_thread=*/false};
  ReidentCore y{options_for(1, s.record.initial), "reident-y@test", /*start_thread=*/false};
  EXPECT_EQ(x.axis(), 0);
  EXPECT_EQ(y.axis(), 1);
  s.send(1.0, {s.into(x), s.into(y)});

  const RefitDecision dx = refit(x, s.now);
  const RefitDecision dy = refit(y, s.now);
  ASSERT_EQ(dx.kind, Kind::accepted) << to_string(dx.status);
  ASSERT_EQ(dy.kind, Kind::accepted) << to_string(dy.status);
  EXPECT_LT(rel_err(dx.candidate.c1, s.record.truth_x.c1), 0.01);
  EXPECT_LT(rel_err(dy.candidate.c1, s.record.truth_y.c1), 0.01);
  // Not the other axis's set, nor a blend of both.
  EXPECT_GT(rel_err(dx.candidate.c1, s.record.truth_y.c1), 0.1);
  EXPECT_GT(rel_err(dy.candidate.c1, s.record.truth_x.c1), 0.1);
  for (ReidentCore* core : {&x, &y}) {
    const ReidentCounters& c = core->counters();
    EXPECT_EQ(c.get(ReidentCounter::samples_fed), 10000u);
    EXPECT_EQ(c.get(ReidentCounter::sensor_blocks_wrong_axes), 0u);
    EXPECT_EQ(c.get(ReidentCounter::non_finite), 0u);
  }
}

TEST(ReidentAxes, ABlockWithoutTheAxisIsRefusedWholeCountedAndNoGap) {
  XyStream s;
  ReidentCore y{options_for(1, s.record.initial), "reident-y@test", /*start_thread=*/false};
  s.send(0.01, {s.into(y)});  // ticks 0 .. 99
  // A one-axis block (a bridge restarted with bridge.axes 1, or another rig's): no y in it.
  sensor_block_t x_only = testdata::reserved_sensor_block();
  testdata::fill_sensor_block(x_only, s.seq, s.now, s.record.x.u, s.record.x.y, s.position, kBlockTicks);
  EXPECT_FALSE(y.on_sensor_block(x_only, s.now));
  s.seq += static_cast<std::int64_t>(kBlockTicks);
  s.position += kBlockTicks;
  s.send(0.001, {s.into(y)});  // ticks 110 .. 119
  const ReidentCounters& c = y.counters();
  EXPECT_EQ(c.get(ReidentCounter::sensor_blocks_wrong_axes), 1u);
  // As a block refused on the wire: one poison marker (no refit straddles it), its ticks no gap.
  EXPECT_EQ(c.get(ReidentCounter::samples_fed), 100u + 1u + 10u);
  EXPECT_EQ(c.get(ReidentCounter::non_finite), 1u);
  EXPECT_EQ(c.get(ReidentCounter::seq_gaps), 0u);
  EXPECT_EQ(c.get(ReidentCounter::samples_missed), 0u);
  // A block that has the axis is taken.
  fill_xy_block(s.block, s.seq, s.now, s.record, s.position, kBlockTicks);
  EXPECT_TRUE(y.on_sensor_block(s.block, s.now));
}

TEST(ReidentAxes, TheAppliedVersionIsReadFromTheAxissCommandTicksAndEachAxisNumbersAboveItsOwn) {
  XyStream s;
  ReidentCore x{options_for(0, s.record.initial), "reident@test", /*start_thread=*/false};
  ReidentCore y{options_for(1, s.record.initial), "reident-y@test", /*start_thread=*/false};
  command_block_t cmd = testdata::reserved_command_block();
  fill_xy_commands(cmd, 0, 300, 3, 9);  // the compensator applies x's version 3 and y's version 9
  x.on_command_block(cmd);
  y.on_command_block(cmd);
  // A one-axis command block says nothing about y.
  testdata::fill_command_block(cmd, 300, 10, 20);
  y.on_command_block(cmd);
  s.send(0.02, {s.into(x), s.into(y)});
  EXPECT_EQ(x.in_use().applied_version(), 3);
  EXPECT_EQ(y.in_use().applied_version(), 9);

  s.send(1.0, {s.into(x), s.into(y)});
  const RefitDecision dx = refit(x, s.now);
  const RefitDecision dy = refit(y, s.now);
  ASSERT_EQ(dx.kind, Kind::accepted) << to_string(dx.status);
  ASSERT_EQ(dy.kind, Kind::accepted) << to_string(dy.status);
  EXPECT_EQ(dx.version, 4);
  EXPECT_EQ(dy.version, 10);
}

TEST(ReidentAxes, ASetForAnotherAxisIsNeitherAdoptedNorFollowedNorCountedForged) {
  XyStream s;
  ReidentCore y{options_for(1, s.record.initial), "reident-y@test", /*start_thread=*/false};
  const std::int64_t own = y.in_use().own_publisher_id();
  // x's re-identifier's set, and one for x under our own publisher id with a version we never
  // published: for y either would be adopted or forged.
  EXPECT_EQ(y.on_params(0, s.record.truth_x, 5, kOtherPublisher, true, "reidentifier@lab"), ParamsOffer::other_axis);
  EXPECT_EQ(y.on_params(0, s.record.truth_x, 40, own, true, "reidentifier@lab"), ParamsOffer::other_axis);
  EXPECT_EQ(y.on_params(2, s.record.truth_x, 41, own, true, "reidentifier-z@lab"), ParamsOffer::other_axis);
  EXPECT_EQ(y.in_use().version(), 1);
  EXPECT_DOUBLE_EQ(y.in_use().params().c1, s.record.initial.c1);
  EXPECT_EQ(y.in_use().forged_sets(), 0u);
  const ReidentCounters& c = y.counters();
  EXPECT_EQ(c.get(ReidentCounter::params_other_axis), 3u);
  EXPECT_EQ(c.get(ReidentCounter::params_adopted), 0u);
  EXPECT_EQ(c.get(ReidentCounter::params_invalid), 0u);
  EXPECT_EQ(c.get(ReidentCounter::params_stale), 0u);

  // Their versions are not followed: y numbers its own sets from its own sequence.
  s.send(1.0, {s.into(y)});
  const RefitDecision d = refit(y, s.now);
  ASSERT_EQ(d.kind, Kind::accepted) << to_string(d.status);
  EXPECT_EQ(d.version, 2);

  // The same sets for y are y's business: adopted, and forged under our id.
  EXPECT_EQ(y.on_params(1, s.record.truth_y, 5, kOtherPublisher, true, "identify@lab"), ParamsOffer::adopted);
  EXPECT_EQ(y.in_use().version(), 5);
  EXPECT_EQ(y.on_params(1, s.record.truth_y, 40, own, true, "reidentifier-y@lab"), ParamsOffer::forged);
  EXPECT_EQ(y.in_use().forged_sets(), 1u);
  EXPECT_EQ(y.counters().get(ReidentCounter::params_other_axis), 3u);
}

TEST(ReidentAxes, TheBlockPathOfAnyAxisAllocatesNothing) {
  XyStream s;
  ReidentCore y{options_for(1, s.record.initial), "reident-y@test", /*start_thread=*/false};
  ReidentCore z{options_for(2, s.record.initial), "reident-z@test", /*start_thread=*/false};
  command_block_t cmd = testdata::reserved_command_block();
  s.send(0.6, {s.into(y)});
  y.poll(s.now);  // a job in flight: snapshotted
  const std::vector<std::function<void(const sensor_block_t&, std::int64_t)>> both{s.into(y), s.into(z)};
  testing::AllocationCounter counter;
  for (int k = 0; k < 100; ++k) {
    fill_xy_commands(cmd, s.seq + 300, static_cast<std::int64_t>(kBlockTicks), 2, 3);
    y.on_command_block(cmd);
    z.on_command_block(cmd);  // no z: ignored
    s.send(0.001, both);      // z refuses every block
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(z.counters().get(ReidentCounter::sensor_blocks_wrong_axes), 100u);
  EXPECT_EQ(y.in_use().applied_version(), 3);
}

TEST(ReidentAxes, ACoreForNoAxisIsRefused) {
  EXPECT_THROW(ReidentCore(options_for(3, testdata::piezo_truth()), "r", false), ParameterError);
  EXPECT_THROW(ReidentCore(options_for(-1, testdata::piezo_truth()), "r", false), ParameterError);
}

// The service over LCM's in-process provider, driven through its handlers and its timer; a
// listener keeps what it publishes.
struct ServiceRig {
  std::unique_ptr<lcm::LCM> lcm = open_lcm("memq://");
  ChannelNames channels{};
  ReidentService service;
  std::vector<mem_params_t> params;
  std::vector<model_params_t> models;
  std::vector<service_status_t> statuses;
  Subscription<mem_params_t> params_sub;
  Subscription<model_params_t> models_sub;
  Subscription<service_status_t> status_sub;

  explicit ServiceRig(const ReidentOptions& options)
      : service(*lcm, channels, options),
        params_sub(*lcm, channels.params, [this](const mem_params_t& m, std::int64_t) { params.push_back(m); }),
        models_sub(*lcm, channels.model, [this](const model_params_t& m, std::int64_t) { models.push_back(m); }),
        status_sub(*lcm, channels.status, [this](const service_status_t& m, std::int64_t) { statuses.push_back(m); }) {}

  void drain() {
    while (handle_pending(*lcm, std::chrono::microseconds(0), 100000) > 0) {
    }
  }
  // Runs the service's timer (the refit runs on its worker thread) until `done` or 60 s.
  bool tick_until(const std::function<bool()>& done) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (std::chrono::steady_clock::now() < deadline) {
      service.on_tick(0);
      drain();
      if (done()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
  }
  void control(std::int64_t request_id, std::int8_t command, const std::string& target) {
    control_t msg{};
    msg.utime = wall_utime();
    msg.request_id = request_id;
    msg.command = command;
    msg.target = target;
    service.on_control(msg);
    drain();
  }
};

TEST(ReidentAxes, TheServiceIsNamedAfterItsAxisAndXKeepsTheNameToolsKnow) {
  EXPECT_EQ(ReidentService::process_name(0), "reidentifier");
  EXPECT_EQ(ReidentService::process_name(1), "reidentifier-y");
  EXPECT_EQ(ReidentService::process_name(2), "reidentifier-z");
  for (int axis : {0, 1}) {
    ServiceRig r(options_for(axis, testdata::piezo_truth()));
    EXPECT_EQ(r.service.process(), ReidentService::process_name(axis));
    r.service.on_tick(0);  // the first report
    r.drain();
    ASSERT_FALSE(r.statuses.empty());
    EXPECT_EQ(r.statuses.back().process, ReidentService::process_name(axis));
  }
}

TEST(ReidentAxes, TheServiceActsOnRequestsForItsOwnNameOrForAll) {
  ServiceRig r(options_for(1, testdata::piezo_truth()));
  r.control(1, control_t::HOLD_PARAMS, "reidentifier");  // x's re-identifier's
  EXPECT_FALSE(r.service.core().held());
  r.control(2, control_t::HOLD_PARAMS, "reidentifier-y");
  EXPECT_TRUE(r.service.core().held());
  r.control(3, control_t::RELEASE_PARAMS, "");  // to all
  EXPECT_FALSE(r.service.core().held());
}

TEST(ReidentAxes, BlocksWithoutItsAxisAreLoggedNamingTheirAxesAndTheServiceIsDegraded) {
  XyStream s;
  auto out = std::make_shared<std::ostringstream>();
  const auto previous = spdlog::default_logger();
  spdlog::set_default_logger(
      std::make_shared<spdlog::logger>("capture", std::make_shared<spdlog::sinks::ostream_sink_mt>(*out)));
  ServiceRig r(options_for(2, s.record.initial));
  for (std::int64_t k = 0; k < 5; ++k) {  // within a second: one line
    fill_xy_block(s.block, k * 10, s.now, s.record, 0, kBlockTicks);
    r.service.on_sensor_block(s.block);
  }
  r.service.on_tick(0);
  r.drain();
  spdlog::set_default_logger(previous);
  const std::string log = out->str();
  EXPECT_NE(log.find("HX_SENSOR block of 2 axes (x, y) has no z"), std::string::npos) << log;
  EXPECT_EQ(log.find("HX_SENSOR block"), log.rfind("HX_SENSOR block")) << "not rate-limited: " << log;
  ASSERT_FALSE(r.statuses.empty());
  const service_status_t& st = r.statuses.back();
  EXPECT_EQ(st.state, service_status_t::DEGRADED);
  EXPECT_NE(st.detail.find("5 HX_SENSOR blocks without axis z"), std::string::npos) << st.detail;
  EXPECT_EQ(r.service.core().counters().get(ReidentCounter::sensor_blocks_wrong_axes), 5u);
}

TEST(ReidentAxes, TheServicesSetsCarryItsAxisAndItTakesOnlyItsAxisOfTheBlocks) {
  XyStream s;
  ServiceRig r(options_for(1, s.record.initial));
  s.send(1.0, {[&r](const sensor_block_t& b, std::int64_t) { r.service.on_sensor_block(b); }});
  ASSERT_TRUE(r.tick_until([&] { return !r.params.empty(); })) << "no set published";
  const mem_params_t& p = r.params.front();
  EXPECT_EQ(p.axis, 1);
  EXPECT_TRUE(p.valid);
  EXPECT_EQ(p.source.rfind("reidentifier-y@", 0), 0u) << p.source;
  EXPECT_EQ(p.publisher_id, r.service.core().in_use().own_publisher_id());
  EXPECT_LT(rel_err(p.c1, s.record.truth_y.c1), 0.01);
  // Its echo came back as ours, not as another axis's.
  EXPECT_EQ(r.service.core().counters().get(ReidentCounter::params_echo), 1u);
  EXPECT_EQ(r.service.core().counters().get(ReidentCounter::params_other_axis), 0u);
}

TEST(ReidentAxes, TheServicesModelChoiceCarriesItsAxis) {
  XyStream s;
  ReidentOptions options = options_for(1, s.record.initial);
  options.models.enabled = true;
  options.models.period_s = 1.0;
  options.models.pinned = ModelKind::linear;  // fitted and switched to at the first selection
  options.models.selector.decimation = 5;
  ServiceRig r(options);
  s.send(1.0, {[&r](const sensor_block_t& b, std::int64_t) { r.service.on_sensor_block(b); }});
  ASSERT_TRUE(r.tick_until([&] { return !r.models.empty(); })) << "no model published";
  EXPECT_EQ(r.models.front().axis, 1);
  EXPECT_EQ(r.models.front().kind, model_params_t::KIND_LINEAR);
}

}  // namespace
}  // namespace hystloop
