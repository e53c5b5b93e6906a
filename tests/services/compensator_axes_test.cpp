// hystloop-compensator for a stage of several axes: compensator.axes control laws, one per axis,
// answering each sensor block of that many axes with one command block of every axis; blocks of
// another count refused; the configured scan (a raster or a Lissajous figure) taken by every axis
// with the first sample, each its share of C^{-1} r when decoupled; parameter sets for every axis
// at once; the per-block path allocation-free with several axes too.
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "lcm/status_counters.hpp"
#include "compensator/compensator_service.hpp"
#include "hystloop/service_status_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/connection.hpp"
#include "support/allocation_counter.hpp"
#include "support/text.hpp"

namespace hystloop {
namespace {

constexpr std::int64_t kBaseUtime = 1'700'000'000'000'000;
constexpr double kDt = 1e-4;
constexpr double kGain = 6.3e-9;

std::int64_t utime_of(std::int64_t tick) { return kBaseUtime + tick * 100; }

const std::string kConfigDir = std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/";

CompensatorSettings load(const std::string& overrides) {
  Config config = Config::load_file(kConfigDir + "compensator.yaml");
  std::string line;
  for (char c : overrides + "\n") {
    if (c != '\n') {
      line += c;
      continue;
    }
    if (!line.empty()) config.apply_override(line);
    line.clear();
  }
  return load_compensator_settings(config);
}

std::string refusal(const std::string& overrides) {
  try {
    load(overrides);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "accepted";
}

using testing::contains;

TEST(CompensatorAxes, SettingsTakeTheAxesTheDecouplingAndTheScanAndNameWhatTheyRefuse) {
  const CompensatorSettings one = load("");
  EXPECT_EQ(one.axes, 1);
  EXPECT_EQ(one.scan.path, ScanSettings::Path::kNone);
  const CompensatorSettings xy =
      load("compensator.axes=2\ndecoupling.x_to_y=0.03\nscan.path=raster\nscan.lines=16\nscan.line_rate_hz=25");
  EXPECT_EQ(xy.axes, 2);
  EXPECT_EQ(xy.decoupling.matrix()(1, 0), 0.03);
  EXPECT_NEAR(xy.decoupling.inverse_matrix()(1, 0), -0.03, 1e-15);
  EXPECT_EQ(xy.scan.path, ScanSettings::Path::kRaster);
  EXPECT_EQ(xy.scan.raster.lines, 16);
  EXPECT_EQ(xy.scan.raster.line_rate_hz, 25.0);
  EXPECT_TRUE(xy.scan.decouple);
  bool says = false;
  for (const std::string& l : describe(xy)) says = says || contains(l, "scan: raster");
  EXPECT_TRUE(says);

  EXPECT_TRUE(contains(refusal("compensator.axes=4"), "compensator.axes"));
  EXPECT_TRUE(contains(refusal("compensator.axes=2\ndecoupling.x_to_y=0.9"), "decoupling.x_to_y"));
  EXPECT_TRUE(contains(refusal("scan.path=raster"), "two axes"));  // one axis
  EXPECT_TRUE(contains(refusal("compensator.axes=2\nscan.path=spiral"), "scan.path"));
  EXPECT_TRUE(contains(refusal("compensator.axes=2\nscan.path=raster\nscan.slow=jump"), "scan.slow"));
  EXPECT_TRUE(contains(refusal("compensator.axes=2\nscan.path=raster\nscan.lines=1"), "scan.lines"));
  EXPECT_TRUE(contains(refusal("compensator.axes=2\nscan.path=lissajous\nscan.amplitude_m=[1e-7,1e-7,1e-7]\n"
                               "scan.frequency_hz=[5,4,3]"),
                       "scan.amplitude_m"));  // moves z, which an XY stage lacks
  EXPECT_TRUE(contains(refusal("compensator.axes=2\nscan.path=lissajous\nscan.amplitude_m=[1e-7,1e-7]"),
                       "scan."));  // moving axes need frequencies
  EXPECT_EQ(refusal("compensator.axes=2\nscan.path=lissajous\nscan.amplitude_m=[1e-7,1e-7]\n"
                    "scan.frequency_hz=[5,4]"),
            "accepted");
}

// The service on memq for a stage of `axes` axes; a bridge that feeds each axis what it was sent
// (u = the feedforward, y = kGain u) and a listener that keeps every axis's commands.
struct AxesHarness {
  std::unique_ptr<lcm::LCM> lcm = open_lcm("memq://");
  ChannelNames channels{};
  CompensatorService service;
  int axes;
  std::array<std::map<std::int64_t, CommandTick>, kMaxAxes> sent;  // per axis: tick -> its last command
  std::vector<std::int8_t> block_axes;                             // n_axes of every command block
  Subscription<command_block_t> commands;
  sensor_block_t sensor{};

  explicit AxesHarness(const CompensatorSettings& s)
      : service(s, *lcm, channels),
        axes(s.axes),
        commands(*lcm, channels.command, [this](const command_block_t& b, std::int64_t) { record(b); }) {
    reserve_storage(sensor);
  }

  void record(const command_block_t& b) {
    block_axes.push_back(b.n_axes);
    for (std::size_t a = 0; a < axes_of(b); ++a) {
      for_each_tick(
          b, [&](const CommandTick& t) { sent[a][t.seq] = t; }, a);
    }
  }

  const sensor_block_t& build(std::int64_t seq, std::int64_t n) {
    begin_block(sensor, seq, utime_of(seq), kDt, axes);
    for (std::int64_t k = seq; k < seq + n; ++k) {
      std::array<SensorTick, kMaxAxes> t{};
      for (int a = 0; a < axes; ++a) {
        const auto& m = sent[static_cast<std::size_t>(a)];
        const auto it = m.find(k);
        const double u = it == m.end() ? 0.0 : it->second.u_ff_V;
        const double y_ref = it == m.end() ? std::nan("") : it->second.y_ref_m;
        t[static_cast<std::size_t>(a)] = SensorTick{utime_of(k), k, u, u, 0.0, y_ref, kGain * u, 0};
      }
      append_tick(sensor, std::span<const SensorTick>(t).first(static_cast<std::size_t>(axes)));
    }
    return sensor;
  }

  void drain() {
    while (handle_pending(*lcm, std::chrono::microseconds(0), 100000) > 0) {
    }
  }

  void run(std::int64_t from, std::int64_t n, std::int64_t block = 50) {
    for (std::int64_t k = from; k < from + n; k += block) {
      service.on_sensor(build(k, std::min(block, from + n - k)), wall_utime());
      drain();
    }
  }
};

CompensatorSettings raster(bool decouple) {
  CompensatorSettings s = load(
      "compensator.axes=2\ndecoupling.x_to_y=0.03\nscan.path=raster\nscan.lines=8\nscan.line_rate_hz=50\n"
      "scan.start_after_s=0.2\nscan.blend_s=0.05\ncompensator.mode=mem\nscan.decouple=" +
      std::string(decouple ? "true" : "false"));
  return s;
}

TEST(CompensatorAxes, EverySensorBlockOfTheStagesAxesIsAnsweredForEveryAxisAndOthersAreRefused) {
  AxesHarness h(raster(true));
  h.run(0, 500);
  ASSERT_FALSE(h.block_axes.empty());
  for (const std::int8_t n : h.block_axes) ASSERT_EQ(n, 2);
  const std::int64_t horizon = h.service.compensator().config().horizon_ticks;
  EXPECT_EQ(h.sent[0].rbegin()->first, 499 + horizon);  // both axes through the horizon
  EXPECT_EQ(h.sent[1].rbegin()->first, 499 + horizon);
  EXPECT_EQ(h.service.counters().plan_mismatch, 0u);

  // A one-axis block: refused whole, nothing planned, nothing observed.
  sensor_block_t one{};
  begin_block(one, 500, utime_of(500), kDt, 1);
  append_tick(one, SensorTick{utime_of(500), 500, 0.0, 0.0, 0.0, 0.0, 0.0, 0});
  const std::size_t blocks = h.block_axes.size();
  h.service.on_sensor(one, wall_utime());
  h.drain();
  EXPECT_EQ(h.service.counters().sensor_blocks_wrong_axes, 1u);
  EXPECT_EQ(h.block_axes.size(), blocks);
  EXPECT_EQ(h.service.compensator(1).last_seq(), 499);
}

TEST(CompensatorAxes, TheConfiguredRasterIsTakenByEveryAxisAndDecouplingReachesOnlyTheCoupledAxis) {
  AxesHarness dec(raster(true)), cou(raster(false));
  // The raster: 8 lines at 50 lines/s from 0.2 s after the first sample (tick 49): ticks 2049 ..
  // 3649, then a settle.
  dec.run(0, 4000);
  cou.run(0, 4000);
  EXPECT_EQ(dec.service.counters().scans, 1u);
  EXPECT_EQ(cou.service.counters().scans, 1u);
  ASSERT_TRUE(dec.service.compensator(1).scan());
  // Mid-raster: x draws lines (+-0.5 um), y has stepped up through the lines (-0.5 .. +0.5 um).
  std::size_t y_differs = 0;
  double x_span_min = 0, x_span_max = 0, y_min = 1, y_max = -1;
  for (std::int64_t k = 2100; k < 3600; ++k) {
    const CommandTick& dx = dec.sent[0].at(k);
    const CommandTick& cx = cou.sent[0].at(k);
    const CommandTick& dy = dec.sent[1].at(k);
    const CommandTick& cy = cou.sent[1].at(k);
    // x's row of C^{-1} is its own axis: the same commands whether decoupled or not.
    ASSERT_EQ(dx.u_ff_V, cx.u_ff_V) << k;
    ASSERT_EQ(dx.y_ref_m, cx.y_ref_m) << k;
    // y's sensor must read the raster's y either way (the servo's reference) ...
    ASSERT_EQ(dy.y_ref_m, cy.y_ref_m) << k;
    // ... but decoupled, its own displacement leaves room for what x moves it by.
    if (dy.u_ff_V != cy.u_ff_V) ++y_differs;
    x_span_min = std::min(x_span_min, dx.y_ref_m);
    x_span_max = std::max(x_span_max, dx.y_ref_m);
    y_min = std::min(y_min, dy.y_ref_m);
    y_max = std::max(y_max, dy.y_ref_m);
  }
  EXPECT_GT(y_differs, 1000u);
  EXPECT_NEAR(x_span_max - x_span_min, 1e-6, 1e-9);
  EXPECT_GT(y_max - y_min, 0.7e-6);  // lines 0..7 of 8 over 1 um, most of them within the window
  // The decoupled y share is r_y - 0.03 r_x: along the first line (x from -0.5 to +0.5 um, y still)
  // y's own displacement must fall by 30 nm more than without decoupling, a few volts at the
  // stage's local slope (~5-8 nm/V). (The two feedforwards differ by a constant too: their
  // hysteresis branches differ.)
  const auto diff_V = [&](std::int64_t k) { return dec.sent[1].at(k).u_ff_V - cou.sent[1].at(k).u_ff_V; };
  const double change_V = diff_V(2049 + 190) - diff_V(2049 + 10);
  EXPECT_LT(change_V, -2.0);
  EXPECT_GT(change_V, -10.0);
}

mem_params_t params(std::int32_t version, double c1, std::int8_t axis) {
  mem_params_t p{};
  p.version = version;
  p.publisher_id = 7;
  p.c1 = c1;
  p.c2 = 1.5e-12;
  p.c3 = 1.1;
  p.valid = 1;
  p.source = "test";
  p.axis = axis;
  return p;
}

TEST(CompensatorAxes, AParameterSetIsTakenByTheAxisItNames) {
  AxesHarness h(load("compensator.axes=2\ncompensator.mode=mem"));
  h.run(0, 200);
  h.service.on_params(params(2, 2.1e-9, 1));
  EXPECT_EQ(h.service.counters().params_refused, 0u);
  EXPECT_EQ(h.service.compensator(0).counters().params_accepted, 0u);
  EXPECT_EQ(h.service.compensator(1).counters().params_accepted, 1u);
  h.service.on_params(params(3, 2.2e-9, 0));
  EXPECT_EQ(h.service.compensator(0).counters().params_accepted, 1u);
  EXPECT_EQ(h.service.compensator(1).counters().params_accepted, 1u);
  h.service.on_params(params(4, 2.2e-9, 2));  // z: this stage has none
  EXPECT_EQ(h.service.counters().params_refused, 1u);
  EXPECT_EQ(h.service.counters().wrong_axis, 1u);

  // Under a raster, a set that would take y's decoupled share past the slew limit is refused.
  AxesHarness r(raster(true));
  r.run(0, 200);
  r.service.on_params(params(2, 2.1e-9, 1));
  EXPECT_EQ(r.service.counters().params_refused, 1u);
  EXPECT_EQ(r.service.compensator(1).counters().params_accepted, 0u);
}

scan_t raster_message(std::int64_t version) {
  scan_t m{};
  m.version = version;
  m.path = scan_t::RASTER;
  m.fast_axis = 0;
  m.slow_axis = 1;
  m.width_m = 1e-6;
  m.height_m = 1e-6;
  m.lines = 8;
  m.line_rate_Hz = 50.0;
  m.slow_mode = scan_t::STEPS;
  m.settle_s = 0.02;
  m.decouple = 1;
  m.blend_s = 0.05;
  return m;
}

TEST(CompensatorAxes, AScanOnHxScanIsTakenByEveryAxisAndDecidedAsATrajectory) {
  AxesHarness h(load("compensator.axes=2\ndecoupling.x_to_y=0.03\ncompensator.mode=mem"));
  h.service.on_scan(raster_message(4));  // before any sample: where the axes are is not known
  EXPECT_EQ(h.service.counters().trajectory_refused_version, 4);
  h.run(0, 200);
  h.service.on_scan(raster_message(5));
  EXPECT_EQ(h.service.counters().trajectory_version, 5);
  EXPECT_EQ(h.service.counters().scans, 1u);
  h.service.on_scan(raster_message(5));  // a UDP repeat
  EXPECT_EQ(h.service.counters().trajectory_repeats, 1u);
  EXPECT_EQ(h.service.counters().scans, 1u);
  h.run(200, 2500);
  double y_min = 1, y_max = -1;
  for (std::int64_t k = 1000; k < 2500; ++k) {
    y_min = std::min(y_min, h.sent[1].at(k).y_ref_m);
    y_max = std::max(y_max, h.sent[1].at(k).y_ref_m);
  }
  EXPECT_GT(y_max - y_min, 0.7e-6);  // y steps across the raster

  scan_t z = raster_message(6);
  z.slow_axis = 2;  // this stage has no z
  h.service.on_scan(z);
  EXPECT_EQ(h.service.counters().trajectory_refused_version, 6);
  EXPECT_EQ(h.service.counters().scans, 1u);

  AxesHarness one(load(""));  // a one-axis stage: no raster
  one.run(0, 200);
  one.service.on_scan(raster_message(7));
  EXPECT_EQ(one.service.counters().trajectory_refused_version, 7);
}

TEST(CompensatorAxes, ATrajectoryMovesTheAxisItNames) {
  AxesHarness h(load("compensator.axes=2\ncompensator.mode=mem"));
  h.run(0, 200);
  trajectory_t t{};
  t.version = 3;
  t.shape = trajectory_t::SINE;
  t.amplitude_m = 0.2e-6;
  t.frequency_Hz = 10.0;
  t.blend_s = 0.01;
  t.axis = 1;
  h.service.on_trajectory(t);
  h.service.settle_trajectories();
  EXPECT_EQ(h.service.counters().trajectory_version, 3);
  h.run(200, 2000);
  double x_span = 0, y_span = 0;
  for (std::int64_t k = 1000; k < 2000; ++k) {
    x_span = std::max(x_span, std::abs(h.sent[0].at(k).y_ref_m));
    y_span = std::max(y_span, std::abs(h.sent[1].at(k).y_ref_m));
  }
  EXPECT_EQ(x_span, 0.0);
  EXPECT_NEAR(y_span, 0.2e-6, 0.01e-6);
  t.version = 4;
  t.axis = 2;
  h.service.on_trajectory(t);
  h.service.settle_trajectories();
  EXPECT_EQ(h.service.counters().trajectory_refused_version, 4);
  EXPECT_EQ(h.service.counters().wrong_axis, 1u);
}

control_t request(std::int64_t id, std::int8_t command) {
  control_t c{};
  c.request_id = id;
  c.command = command;
  return c;
}

TEST(CompensatorAxes, AnExperimentRunsOnTheAxisItNamesAndAStopEndsItWhicheverAxis) {
  AxesHarness h(load("compensator.axes=2\ncompensator.mode=mem"));
  h.run(0, 200);
  control_t start = request(1, control_t::START_EXPERIMENT);
  start.experiment = "sine";
  start.experiment_amplitude_V = 20.0;
  start.experiment_frequency_Hz = 10.0;
  start.experiment_duration_s = 5.0;
  start.axis = 1;
  h.service.on_control(start);
  h.run(200, 1000);
  EXPECT_TRUE(h.service.compensator(1).experiment_running());
  EXPECT_FALSE(h.service.compensator(0).experiment_running());
  h.service.on_control(request(2, control_t::STOP_EXPERIMENT));
  h.run(1200, 1000);
  EXPECT_FALSE(h.service.compensator(1).experiment_running());
  EXPECT_NE(h.sent[1].rbegin()->second.mode, command_block_t::MODE_EXPERIMENT);
}

TEST(CompensatorAxes, WhileAScanRunsNoAxisLeavesItAlone) {
  AxesHarness h(load("compensator.axes=2\ndecoupling.x_to_y=0.03\ncompensator.mode=mem"));
  h.run(0, 200);
  h.service.on_scan(raster_message(5));
  ASSERT_EQ(h.service.counters().scans, 1u);
  trajectory_t t{};
  t.version = 6;
  t.shape = trajectory_t::HOLD;
  t.blend_s = 0.05;
  h.service.on_trajectory(t);  // x alone would stop while y follows its share of x's motion
  h.service.settle_trajectories();
  EXPECT_EQ(h.service.counters().trajectory_refused_version, 6);
  control_t start = request(3, control_t::START_EXPERIMENT);
  start.experiment = "sine";
  start.experiment_amplitude_V = 20.0;
  start.experiment_frequency_Hz = 10.0;
  start.experiment_duration_s = 1.0;
  h.service.on_control(start);
  EXPECT_FALSE(h.service.compensator(0).experiment_running());
  EXPECT_EQ(h.service.counters().control_refused, 1u);
  h.run(200, 3000);  // past the raster's end: both may move again
  t.version = 7;
  h.service.on_trajectory(t);
  h.service.settle_trajectories();
  EXPECT_EQ(h.service.counters().trajectory_version, 7);
}

TEST(CompensatorAxes, APathTooLongToCheckOnTheLoopsThreadIsRefusedNamingTheLimit) {
  AxesHarness h(load("compensator.axes=2\ncompensator.mode=mem"));
  h.run(0, 200);
  scan_t m{};
  m.version = 9;
  m.path = scan_t::LISSAJOUS;
  m.amplitude_m[0] = m.amplitude_m[1] = 1e-7;
  m.frequency_Hz[0] = 5.0;
  m.frequency_Hz[1] = 4.0;
  m.phase_rad[0] = m.phase_rad[1] = -1.5707963267948966;
  m.duration_s = 4.0;  // 2 axes x 4 s: past the budget
  m.blend_s = 0.05;
  h.service.on_scan(m);
  EXPECT_EQ(h.service.counters().trajectory_refused_version, 9);
  EXPECT_EQ(h.service.counters().scans_refused, 1u);
  m.version = 10;
  m.duration_s = 2.0;
  h.service.on_scan(m);
  EXPECT_EQ(h.service.counters().trajectory_version, 10);
  EXPECT_TRUE(refusal("compensator.axes=2\nscan.path=lissajous\nscan.amplitude_m=[1e-7,1e-7]\n"
                      "scan.frequency_hz=[5,4]\nscan.duration_s=4")
                  .find("scan.duration_s") != std::string::npos);
  EXPECT_TRUE(refusal("compensator.axes=2\nscan.path=raster\nscan.start_after_s=0.05").find("scan.start_after_s") !=
              std::string::npos);
}

TEST(CompensatorAxes, TheStatusOfThreeAxesWithAScanHasEveryCounter) {
  // Every counter fits in one report, down to the resource figures the report's CPU comes from
  // (they are added last): a report cut at MAX_COUNTERS loses them silently.
  AxesHarness h(load("compensator.axes=3\nscan.path=raster\nscan.lines=8"));
  std::vector<service_status_t> reports;
  Subscription<service_status_t> status(*h.lcm, h.channels.status,
                                        [&](const service_status_t& s, std::int64_t) { reports.push_back(s); });
  h.run(0, 200);
  h.service.report(wall_utime(), false);
  h.drain();
  ASSERT_FALSE(reports.empty());
  const service_status_t& r = reports.back();
  EXPECT_LT(r.n_counters, service_status_t::MAX_COUNTERS) << "the report is full: counters were dropped";
  bool cpu = false;
  for (const std::string& n : r.counter_names) cpu = cpu || n == "cpu_user_us";
  EXPECT_TRUE(cpu);
  // Each axis's learning and its set, the others' behind their axis.
  for (const char* name : {"learning_active", "y_learning_active", "z_learning_periods", "z_params_held_by_learning",
                           "y_learning_rms_pm", "z_params_version", "z_learning_divergences"}) {
    EXPECT_TRUE(find_counter(r, name).has_value()) << name;
  }
  EXPECT_NE(r.detail.find("; z: params v"), std::string::npos) << r.detail;
}

TEST(CompensatorAxes, TheSensorBlockPathDoesNotAllocateWithSeveralAxes) {
  AxesHarness h(raster(true));
  h.run(0, 1000);  // warm-up: sizes the publisher's buffer
  std::vector<sensor_block_t> blocks;
  for (std::int64_t seq = 1000; seq < 4000; seq += 50) blocks.push_back(h.build(seq, 50));
  testing::AllocationCounter counter;
  for (const sensor_block_t& b : blocks) h.service.on_sensor(b, b.utime + 20);
  EXPECT_EQ(counter.allocations(), 0u);
  h.drain();
}

}  // namespace
}  // namespace hystloop
