// hystloop-compensator's wiring, driven through its handlers over the in-process memq provider,
// the command blocks read back from HX_COMMAND: each sensor block is answered with the ticks not
// yet sent through its last tick + the horizon (each tick once, in blocks of at most MAX_TICKS),
// allocation-free; the commands are a deterministic function of the messages; parameter sets are
// taken only when valid and newer and swapped at a reversal; a trajectory's version is applied
// once, at its start time when it has one; control requests that are not the compensator's are
// refused or ignored; a bridge restart restarts the control law; old config keys say where they went.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "compensator/compensator_service.hpp"
#include "compensator/trajectory_message.hpp"
#include "lcm/blocks.hpp"
#include "hystloop/service_status_t.hpp"
#include "lcm/connection.hpp"
#include "support/allocation_counter.hpp"
#include "support/text.hpp"

#include <sstream>

#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

namespace hystloop {
namespace {

constexpr std::int64_t kBaseUtime = 1'700'000'000'123'456;  // the bridge's wall clock at its tick 0 [us]
constexpr double kDt = 1e-4;
constexpr std::int64_t kHorizon = 300;  // 30 ms (fixed here: the deployed value is tuned elsewhere)
constexpr double kGain = 6.3e-9;        // a crude plant: y follows u with the stage's mean slope

std::int64_t utime_of(std::int64_t tick) { return kBaseUtime + tick * 100; }

const std::string kConfigDir = std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/";

CompensatorSettings deployed() { return load_compensator_settings(Config::load_file(kConfigDir + "compensator.yaml")); }

// The deployed settings, in MEM mode (the MEM paper's workflow, whose parameter swaps these test),
// holding at 0, with a horizon of kHorizon ticks.
CompensatorSettings holding() {
  CompensatorSettings s = deployed();
  s.control.horizon_ticks = kHorizon;
  s.control.mode = FeedforwardMode::kMem;
  // These harnesses test when things take effect, with steps no actuator could follow: without
  // the actuator's limits (tests/loop/compensator_limits_test.cpp has them), the re-anchoring
  // ramp as fast as with them.
  const CompensatorConfig real = s.control;
  s.control.u_min_V = -1e6;
  s.control.u_max_V = 1e6;
  s.control.slew_V_per_s = 1e12;
  s.control.slew_fraction = real.slew_fraction * real.slew_V_per_s / s.control.slew_V_per_s;
  // The plausible gain band is taken over the actuator's range, which these harnesses remove: as
  // wide as it goes (compensator_plausibility_test.cpp checks it on the deployed range).
  s.plausible_gain_factor = GainPlausibility::kMaxFactor;
  return s;
}

// The MEM paper's reference, -1.6 um cos(2 pi t), approached over 50 ms from the first tick
// planned. Its first reversal (the minimum) is 50 ms after that tick, the next 0.5 s later.
CompensatorSettings cosine() {
  CompensatorSettings s = holding();
  s.trajectory.shape = TrajectoryShape::kCosine;
  s.trajectory.amplitude_m = -1.6e-6;
  s.trajectory.blend_s = 0.05;
  return s;
}

control_t request(std::int64_t id, std::int8_t command, const std::string& target = "") {
  control_t c{};
  c.request_id = id;
  c.command = command;
  c.target = target;
  return c;
}

constexpr std::int64_t kReident = 0x7e1d'0001;  // the re-identifier's publisher id

mem_params_t params(std::int32_t version, double c1, bool valid = true, std::int64_t publisher = kReident) {
  mem_params_t p{};
  p.version = version;
  p.publisher_id = publisher;
  p.c1 = c1;
  p.c2 = 1.5e-12;
  p.c3 = 1.1;
  p.valid = valid ? 1 : 0;
  p.source = "test";
  return p;
}

struct BlockSeen {
  std::int64_t seq;
  std::int32_t n_ticks;
  std::int64_t sample_seq;
};

// The service on a memq LCM, a bridge that feeds it sensor blocks (u = the feedforward it was
// sent for the tick, 0 when none; y = kGain u) and a listener on HX_COMMAND.
struct Harness {
  std::unique_ptr<lcm::LCM> lcm = open_lcm("memq://");
  ChannelNames channels{};
  CompensatorService service;
  std::vector<BlockSeen> blocks;               // every command block published, in order
  std::vector<CommandTick> ticks;              // their ticks, in order
  std::map<std::int64_t, std::size_t> latest;  // tick -> its last entry in `ticks`
  Subscription<command_block_t> commands;
  sensor_block_t sensor{};
  double plant_gain = kGain;  // y = plant_gain u [m/V]

  explicit Harness(const CompensatorSettings& s = cosine())
      : service(s, *lcm, channels),
        commands(*lcm, channels.command, [this](const command_block_t& b, std::int64_t) { record(b); }) {
    reserve_storage(sensor);
  }

  void record(const command_block_t& b) {
    blocks.push_back({b.seq, b.n_ticks, b.sample_seq});
    for_each_tick(b, [&](const CommandTick& t) {
      latest[t.seq] = ticks.size();
      ticks.push_back(t);
    });
  }

  // Sensor block of ticks [seq, seq + n).
  const sensor_block_t& build(std::int64_t seq, std::int64_t n, std::int32_t flags = 0) {
    begin_block(sensor, seq, utime_of(seq), kDt);
    for (std::int64_t k = seq; k < seq + n; ++k) {
      const auto it = latest.find(k);
      const double u = it == latest.end() ? 0.0 : ticks[it->second].u_ff_V;
      const double y_ref = it == latest.end() ? std::nan("") : ticks[it->second].y_ref_m;
      append_tick(sensor, SensorTick{utime_of(k), k, u, u, 0.0, y_ref, plant_gain * u, flags});
    }
    return sensor;
  }

  void drain() {
    while (handle_pending(*lcm, std::chrono::microseconds(0), 100000) > 0) {
    }
  }

  void send(std::int64_t seq, std::int64_t n = 10) {
    service.on_sensor(build(seq, n), wall_utime());
    drain();
  }

  // Ticks [from, from + n) in blocks of `block`.
  void run(std::int64_t from, std::int64_t n, std::int64_t block = 10) {
    for (std::int64_t k = from; k < from + n; k += block) send(k, std::min(block, from + n - k));
  }

  // The command last sent for a tick.
  const CommandTick& tick(std::int64_t seq) const {
    const auto it = latest.find(seq);
    if (it == latest.end()) throw std::out_of_range("no command for tick " + std::to_string(seq));
    return ticks[it->second];
  }
  std::int64_t sent_through() const { return ticks.empty() ? -1 : ticks.back().seq; }
};

// One HX_STATUS report of the service, as a listener on its channel receives it: the message and
// its counters by name.
struct Reported {
  service_status_t status{};
  std::map<std::string, std::int64_t> counters;
};
Reported report_status(Harness& h) {
  h.drain();  // reports published before (a verdict's immediate one) are not this one
  Subscription<service_status_t> listener(*h.lcm, h.channels.status);
  h.service.report(wall_utime(), false);
  h.drain();
  EXPECT_EQ(listener.counters().accepted, 1u);
  Reported r{listener.latest(), {}};
  for (std::size_t i = 0; i < r.status.counter_names.size(); ++i) {
    r.counters[r.status.counter_names[i]] = r.status.counter_values[i];
  }
  return r;
}

// After a sensor block whose last tick is `last`, the blocks published since `from_block` carry
// exactly the ticks after `before` (the last one sent) and after `last` (the bridge has passed
// it) through last + horizon: consecutive, each once, at most MAX_TICKS per block, each stamped
// with the sample it answered.
void expect_answer(const Harness& h, std::size_t from_block, std::int64_t before, std::int64_t last,
                   std::int64_t horizon = kHorizon) {
  std::int64_t next = std::max(before, last) + 1;
  for (std::size_t i = from_block; i < h.blocks.size(); ++i) {
    const BlockSeen& b = h.blocks[i];
    EXPECT_EQ(b.seq, next) << "block " << i;
    EXPECT_GE(b.n_ticks, 1);
    EXPECT_LE(b.n_ticks, command_block_t::MAX_TICKS);
    EXPECT_EQ(b.sample_seq, last);
    next = b.seq + b.n_ticks;
  }
  EXPECT_EQ(next - 1, std::max(before, last + horizon)) << "after the sample of tick " << last;
}

TEST(CompensatorService, AnswersEachSensorBlockWithTheTicksNotYetSentThroughTheHorizon) {
  Harness h;
  // The first block: the whole horizon after it, in one block.
  h.send(5000);
  ASSERT_EQ(h.blocks.size(), 1u);
  EXPECT_EQ(h.blocks[0].seq, 5010);
  EXPECT_EQ(h.blocks[0].n_ticks, kHorizon);
  EXPECT_EQ(h.blocks[0].sample_seq, 5009);
  // Then each block of 10 is answered with the 10 ticks now inside the horizon.
  for (std::int64_t seq = 5010; seq < 6000; seq += 10) {
    const std::size_t b = h.blocks.size();
    h.send(seq);
    ASSERT_EQ(h.blocks.size(), b + 1) << seq;
    EXPECT_EQ(h.blocks[b].seq, seq + kHorizon);
    EXPECT_EQ(h.blocks[b].n_ticks, 10);
    EXPECT_EQ(h.blocks[b].sample_seq, seq + 9);
  }
  // Whatever the bridge's block size (1 is allowed), lost blocks and repeated ones.
  struct Step {
    std::int64_t seq, n;
  };
  const Step steps[] = {{6000, 1},   {6001, 1},  {6002, 1},  {6003, 7},
                        {6010, 25},  {6035, 10}, {6065, 10},  // 20 ticks lost: 30 ticks answered
                        {6065, 10},                           // the same block again: nothing new to send
                        {6050, 10},                           // an old one: nothing either
                        {6075, 250}, {6325, 10}};
  for (const Step& s : steps) {
    const std::size_t b = h.blocks.size();
    const std::int64_t before = h.sent_through();
    h.send(s.seq, s.n);
    expect_answer(h, b, before, s.seq + s.n - 1);
  }
  EXPECT_EQ(h.service.compensator().counters().out_of_order, 20u);
  EXPECT_EQ(h.service.compensator().counters().gaps, 20u);

  // A stall longer than the horizon (every block lost for 40 ms): a jump, believed once three
  // blocks confirm it (SequenceGuard); then the ticks the bridge passed are not sent any more.
  const std::uint64_t behind = h.service.compensator().counters().ticks_behind;
  const std::size_t b = h.blocks.size();
  const std::int64_t before = h.sent_through();  // 6334 + 300; the bridge is now at before + 100
  h.send(before + 100);
  h.send(before + 110);
  EXPECT_EQ(h.blocks.size(), b);
  h.send(before + 120);
  expect_answer(h, b, before + 129, before + 129);
  EXPECT_EQ(h.service.compensator().counters().ticks_behind - behind, 129u);
  EXPECT_EQ(h.service.sequence_counters().jumps, 1u);

  // No tick was sent twice; every tick from the first on was sent, but those the stall skipped.
  for (std::size_t i = 1; i < h.ticks.size(); ++i) {
    if (h.ticks[i].seq == before + 130) continue;
    ASSERT_EQ(h.ticks[i].seq, h.ticks[i - 1].seq + 1) << "entry " << i;
  }
  const CompensatorServiceCounters& c = h.service.counters();
  EXPECT_EQ(c.command_blocks_published, h.blocks.size());
  EXPECT_EQ(c.command_ticks_published, h.ticks.size());
  EXPECT_EQ(h.commands.counters().received, h.blocks.size());  // none failed the receiver's checks

  // What a tick carries: MEM feedforward on the cosine, which started 50 ms after the first
  // tick planned (5010).
  const CommandTick& t = h.tick(6000);
  EXPECT_EQ(t.mode, command_block_t::MODE_MEM);
  EXPECT_EQ(t.params_version, 0);
  EXPECT_NEAR(t.y_ref_m, -1.6e-6 * std::cos(2.0 * std::numbers::pi * (0.6 - (0.501 + 0.05))), 1e-12);
  EXPECT_EQ(h.tick(5010).y_ref_m, 0.0);  // the approach starts where the reference was
  for (const CommandTick& k : h.ticks) ASSERT_TRUE(std::isfinite(k.u_ff_V) && std::isfinite(k.y_ref_m)) << k.seq;
}

TEST(CompensatorService, AnswersLongerThanMaxTicksAreSplitIntoBlocks) {
  CompensatorSettings s = cosine();
  s.control.horizon_ticks = 2500;
  Harness h(s);
  h.send(0);
  ASSERT_EQ(h.blocks.size(), 3u);
  EXPECT_EQ(h.blocks[0].n_ticks, command_block_t::MAX_TICKS);
  EXPECT_EQ(h.blocks[1].n_ticks, command_block_t::MAX_TICKS);
  EXPECT_EQ(h.blocks[2].n_ticks, 500);
  expect_answer(h, 0, 9, 9, 2500);
  std::size_t b = h.blocks.size();
  h.send(10);
  expect_answer(h, b, 2509, 19, 2500);
  EXPECT_EQ(h.blocks.back().n_ticks, 10);
  // After a long stall (confirmed by three blocks) the whole horizon again, split the same way.
  b = h.blocks.size();
  h.send(10000);
  h.send(10010);
  h.send(10020);
  ASSERT_EQ(h.blocks.size(), b + 3);
  expect_answer(h, b, 10029, 10029, 2500);
  EXPECT_EQ(h.commands.counters().received, h.blocks.size());
}

// A clean start has no tick "planned too late": the first block's earlier ticks were never due.
TEST(CompensatorService, AFirstBlockCountsNoTicksBehind) {
  Harness h;
  h.run(5000, 1000);
  EXPECT_EQ(h.service.compensator().counters().ticks_behind, 0u);
}

// A sensor block of two axes reaching a one-axis compensator: refused whole and counted, never read
// as x (its arrays would be two axes interleaved, read as twice the ticks).
TEST(CompensatorService, ASensorBlockOfAnotherNumberOfAxesIsRefusedNotGuessed) {
  Harness h;
  h.run(0, 100);
  const std::size_t published = h.ticks.size();
  sensor_block_t xy{};
  begin_block(xy, 100, utime_of(100), kDt, 2);
  for (std::int64_t k = 100; k < 110; ++k) {
    const std::array<SensorTick, 2> axes{SensorTick{utime_of(k), k, 1.0, 1.0, 0.0, 0.0, 1e-9, 0},
                                         SensorTick{utime_of(k), k, 2.0, 2.0, 0.0, 0.0, 2e-9, 0}};
    ASSERT_TRUE(append_tick(xy, axes));
  }
  h.service.on_sensor(xy, wall_utime());
  h.drain();
  EXPECT_EQ(h.service.counters().sensor_blocks_wrong_axes, 1u);
  EXPECT_EQ(h.ticks.size(), published);  // nothing planned from it
  EXPECT_EQ(h.service.compensator().last_seq(), 99);
  h.send(100);  // the stream goes on with blocks of its own axis count
  EXPECT_EQ(h.service.compensator().last_seq(), 109);
}

// Counts operator new in this thread. LCM's C core allocates with malloc (memq copies each
// message into a queue entry), which the counter does not see.
TEST(CompensatorService, TheSensorBlockPathDoesNotAllocate) {
  Harness h;
  h.run(0, 1000);                          // warm-up: the first answer (a whole horizon) sizes the publisher's buffer
  h.service.on_params(params(2, 5.5e-9));  // swapped in at the reversal near tick 5510, below
  std::vector<sensor_block_t> blocks;
  for (std::int64_t seq = 1000; seq < 7000; seq += 10) {
    blocks.push_back(h.build(seq, 10));
    for (std::size_t i = 0; i < 10; ++i) {
      blocks.back().u_V[i] = 10.0;
      blocks.back().y_m[i] = 6e-8;
    }
  }
  const std::uint64_t published = h.service.counters().command_blocks_published;
  testing::AllocationCounter counter;
  for (const sensor_block_t& b : blocks) h.service.on_sensor(b, b.utime + 20);
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(h.service.counters().command_blocks_published - published, blocks.size());
  EXPECT_EQ(h.service.compensator().counters().params_swapped, 1u);
  h.drain();
}

std::uint64_t bits(double x) { return std::bit_cast<std::uint64_t>(x); }

void script(Harness& h) {
  trajectory_t t{};
  t.version = 3;
  t.shape = trajectory_t::TRIANGLE;
  t.amplitude_m = 1e-6;
  t.frequency_Hz = 5.0;
  t.blend_s = 0.01;
  h.run(100, 500);
  h.service.on_trajectory(t);
  h.service.settle_trajectories();
  h.service.on_params(params(2, 5.5e-9));
  h.run(600, 3000, 10);
  control_t c = request(1, control_t::SET_MODE);
  c.mode = command_block_t::MODE_PI;
  h.service.on_control(c);
  h.run(3600, 500, 7);
  c = request(2, control_t::START_EXPERIMENT);
  c.experiment = "sine";
  c.experiment_amplitude_V = 50.0;
  c.experiment_frequency_Hz = 20.0;
  c.experiment_duration_s = 0.05;
  h.service.on_control(c);
  h.run(4100, 1500, 25);
  for (std::int8_t mode : {command_block_t::MODE_KATALENIC, command_block_t::MODE_LINEAR, command_block_t::MODE_OFF,
                           command_block_t::MODE_MEM}) {
    c = request(10 + mode, control_t::SET_MODE);
    c.mode = mode;
    h.service.on_control(c);
    h.run(h.service.compensator().last_seq() + 1, 400);
  }
}

TEST(CompensatorService, CommandsAreADeterministicFunctionOfTheMessages) {
  Harness a, b;
  script(a);
  script(b);
  ASSERT_GT(a.ticks.size(), 5000u);
  ASSERT_EQ(a.ticks.size(), b.ticks.size());
  ASSERT_EQ(a.blocks.size(), b.blocks.size());
  for (std::size_t i = 0; i < a.blocks.size(); ++i) {  // (a block's utime is when it was published)
    ASSERT_EQ(a.blocks[i].seq, b.blocks[i].seq) << i;
    ASSERT_EQ(a.blocks[i].n_ticks, b.blocks[i].n_ticks) << i;
    ASSERT_EQ(a.blocks[i].sample_seq, b.blocks[i].sample_seq) << i;
  }
  std::vector<bool> modes(6, false);
  for (std::size_t i = 0; i < a.ticks.size(); ++i) {
    const CommandTick &x = a.ticks[i], &y = b.ticks[i];
    ASSERT_EQ(x.seq, y.seq);
    ASSERT_EQ(bits(x.u_ff_V), bits(y.u_ff_V)) << x.seq;
    ASSERT_EQ(bits(x.y_ref_m), bits(y.y_ref_m)) << x.seq;  // NaN included
    ASSERT_EQ(x.params_version, y.params_version) << x.seq;
    ASSERT_EQ(x.mode, y.mode) << x.seq;
    modes[static_cast<std::size_t>(x.mode)] = true;
  }
  EXPECT_EQ(modes, std::vector<bool>(6, true));  // every mode and an experiment were exercised
  EXPECT_EQ(a.service.counters().trajectories, 1u);
  EXPECT_EQ(a.service.compensator().counters().nonfinite_outputs, 0u);
}

// True when the reference turns at entry i of h.ticks (a reversal of the planned reference).
bool turns_at(const Harness& h, std::size_t i) {
  const double d1 = h.ticks[i].y_ref_m - h.ticks[i - 1].y_ref_m;
  const double d0 = h.ticks[i - 1].y_ref_m - h.ticks[i - 2].y_ref_m;
  return d1 * d0 < 0.0;
}

std::size_t first_with_version(const Harness& h, std::int32_t version) {
  for (std::size_t i = 0; i < h.ticks.size(); ++i) {
    if (h.ticks[i].params_version == version) return i;
  }
  return h.ticks.size();
}

TEST(CompensatorService, TakesOnlyValidNewerParameterSetsAndSwapsThemAtAReversal) {
  Harness h;
  h.send(0);  // planned through 309; the cosine's minimum is at tick 510
  h.service.on_params(params(2, 5.5e-9, false));
  EXPECT_EQ(h.service.counters().params_invalid, 1u);
  h.service.on_params(params(2, 5.5e-9));
  EXPECT_EQ(h.service.compensator().counters().params_accepted, 1u);
  h.service.on_params(params(2, 5.5e-9));  // the same version again
  h.service.on_params(params(1, 4.0e-9));  // an older one
  EXPECT_EQ(h.service.counters().params_stale, 2u);
  h.service.on_params(params(3, -1e-9));  // outside the model's domain: the compensator's own validation
  EXPECT_EQ(h.service.counters().params_refused, 1u);
  EXPECT_EQ(h.service.compensator().params_version(), 0);  // not before a reversal

  h.run(10, 2990);
  std::size_t i = first_with_version(h, 2);
  ASSERT_LT(i, h.ticks.size());
  EXPECT_TRUE(turns_at(h, i)) << "v2 first used at tick " << h.ticks[i].seq;
  EXPECT_GE(h.ticks[i].seq, 505);
  EXPECT_LE(h.ticks[i].seq, 515);
  for (std::size_t j = 0; j < h.ticks.size(); ++j) ASSERT_EQ(h.ticks[j].params_version, j < i ? 0 : 2) << j;
  EXPECT_EQ(h.service.compensator().params_version(), 2);
  EXPECT_EQ(h.service.compensator().mem_params().c1, 5.5e-9);

  h.service.on_params(params(4, 6.0e-9));  // the next, at the next reversal (the maximum, tick 5510)
  h.run(3000, 3000);
  const std::size_t k = first_with_version(h, 4);
  ASSERT_LT(k, h.ticks.size());
  EXPECT_TRUE(turns_at(h, k)) << "v4 first used at tick " << h.ticks[k].seq;
  EXPECT_GE(h.ticks[k].seq, 5505);
  EXPECT_LE(h.ticks[k].seq, 5515);
  for (std::size_t j = i; j < h.ticks.size(); ++j) ASSERT_EQ(h.ticks[j].params_version, j < k ? 2 : 4) << j;
  EXPECT_EQ(h.service.compensator().mem_params().c1, 6.0e-9);
  EXPECT_EQ(h.service.compensator().counters().params_swapped, 2u);
  EXPECT_EQ(first_with_version(h, 3), h.ticks.size());  // the refused one never
}

// one set with the largest version from anyone (or a re-identifier's earlier run)
// must not freeze the re-identifier out: versions are ordered per publisher only.
TEST(CompensatorService, AHugeVersionFromOnePublisherDoesNotFreezeTheReidentifiersLaterSets) {
  Harness h;
  h.send(0);
  constexpr std::int64_t kForger = 0x0bad;
  h.service.on_params(params(std::numeric_limits<std::int32_t>::max(), 4.0e-9, true, kForger));
  EXPECT_EQ(h.service.compensator().counters().params_accepted, 1u);
  h.service.on_params(params(2, 5.0e-9));  // the re-identifier's, versions far below
  h.service.on_params(params(3, 5.5e-9));
  EXPECT_EQ(h.service.compensator().counters().params_accepted, 3u);
  EXPECT_EQ(h.service.counters().params_stale, 0u);
  h.service.on_params(params(3, 5.5e-9));  // its UDP repeat
  h.service.on_params(params(2, 5.0e-9));  // an older one of its own
  EXPECT_EQ(h.service.counters().params_stale, 2u);
  h.run(10, 990);  // past the reversal near tick 510: the last set offered is swapped in
  EXPECT_EQ(h.service.compensator().params_version(), 3);
  EXPECT_EQ(h.service.compensator().mem_params().c1, 5.5e-9);
  EXPECT_EQ(h.tick(h.sent_through()).params_version, 3);

  // The re-identifier restarted: a new id, its counter from the start again.
  h.service.on_params(params(2, 6.0e-9, true, kReident + 1));
  EXPECT_EQ(h.service.compensator().counters().params_accepted, 4u);
  EXPECT_EQ(h.service.counters().params_stale, 2u);
  h.service.report(wall_utime(), false);
}

// a forged sensor block 900 ticks ahead made the compensator skip ahead and drop the
// real blocks that followed (~50 ms without commands). It is held, then ignored.
TEST(CompensatorService, AForgedSensorBlockFarAheadIsIgnoredAndTheRealBlocksAreAnswered) {
  Harness h;
  h.run(0, 1000);
  const std::size_t from_block = h.blocks.size();
  const std::int64_t sent = h.sent_through();
  h.send(1000 + 900);                      // forged
  EXPECT_EQ(h.blocks.size(), from_block);  // not answered
  EXPECT_EQ(h.service.compensator().last_seq(), 999);
  h.send(1000);
  expect_answer(h, from_block, sent, 1009);
  h.run(1010, 990);
  const CompensatorCounters& c = h.service.compensator().counters();
  EXPECT_EQ(c.out_of_order, 0u);
  EXPECT_EQ(c.ticks_behind, 0u);
  EXPECT_EQ(c.gaps, 0u);
  EXPECT_EQ(c.samples, 2000u);
  EXPECT_EQ(h.service.compensator().last_seq(), 1999);
  EXPECT_EQ(h.sent_through(), 1999 + kHorizon);
  EXPECT_EQ(h.service.sequence_counters().ignored, 1u);
  EXPECT_EQ(h.service.sequence_counters().held, 1u);
  EXPECT_EQ(h.service.sequence_counters().jumps, 0u);
}

// one 5,000 ticks behind silently restarted the control law and reset its counters.
TEST(CompensatorService, AForgedSensorBlockFarBehindDoesNotRestartTheControlLaw) {
  Harness h;
  h.run(50000, 1000);
  control_t c = request(1, control_t::SET_MODE);
  c.mode = command_block_t::MODE_PI;
  h.service.on_control(c);
  const std::uint64_t samples = h.service.compensator().counters().samples;
  h.send(51000 - 5000);
  h.send(51000 - 5000 + 10);  // two consistent ones are not enough either
  h.run(51000, 1000);
  EXPECT_EQ(h.service.counters().bridge_restarts, 0u);
  EXPECT_EQ(h.service.sequence_counters().ignored, 1u);
  EXPECT_EQ(h.service.compensator().counters().samples, samples + 1000);
  EXPECT_EQ(h.service.compensator().counters().out_of_order, 0u);
  EXPECT_EQ(h.service.compensator().mode(), FeedforwardMode::kPi);
  EXPECT_EQ(h.sent_through(), 51999 + kHorizon);
}

// 5,804 log lines a minute under malformed input, with raw control bytes from the
// messages. Repeated warnings are rate-limited (the next line says how many were suppressed),
// and text off the wire is escaped.
TEST(CompensatorService, RepeatedWarningsAreRateLimitedAndWireTextIsEscaped) {
  auto out = std::make_shared<std::ostringstream>();
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(*out);
  const auto previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>("capture", sink));
  {
    Harness h;
    for (std::int64_t id = 1; id <= 1000; ++id) {
      control_t c = request(id, control_t::START_EXPERIMENT);
      c.experiment = "evil\x1b[2J\n\r";  // not a known experiment: refused, its name in the reason
      c.experiment_amplitude_V = 10.0;
      c.experiment_frequency_Hz = 1.0;
      c.experiment_duration_s = 1.0;
      h.service.on_control(c);
    }
    for (std::int32_t v = 1; v <= 500; ++v) {  // 500 publishers' invalid sets, and one's stale repeats
      h.service.on_params(params(v, 5e-9, false, 1000 + v));
      h.service.on_params(params(1, 5e-9, true, 7));
    }
    EXPECT_EQ(h.service.counters().control_refused, 1000u);
    EXPECT_EQ(h.service.counters().params_invalid, 500u);
    EXPECT_EQ(h.service.counters().params_stale, 499u);
    std::map<std::string, std::int64_t> reported = report_status(h).counters;
    EXPECT_EQ(reported["params_invalid"], 500);
    EXPECT_EQ(reported["params_stale"], 499);
    EXPECT_EQ(reported["control_refused"], 1000);
    EXPECT_EQ(reported["params_publishers_evicted"], 500 + 1 - 16);  // 501 publishers in a table of 16
    // 999 control refusals; 499 invalid sets (each publisher's first is due, one a second is written).
    EXPECT_EQ(reported["log_lines_suppressed"], 999 + 499);
  }
  spdlog::set_default_logger(previous);
  const std::string log = out->str();
  std::size_t lines = 0;
  for (const char c : log) lines += c == '\n';
  // The loop takes well under a second: one control refusal, one invalid set (once per publisher,
  // and of those one a second), one stale set, one accepted.
  EXPECT_LE(lines, 4u) << log.substr(0, 2000);
  EXPECT_EQ(log.find('\x1b'), std::string::npos);
  EXPECT_EQ(log.find('\r'), std::string::npos);
  EXPECT_NE(log.find("evil\\x1b[2J\\x0a\\x0d"), std::string::npos) << log.substr(0, 2000);
}

// A real jump ahead (the bridge's clock skipped) is believed once three blocks confirm it.
TEST(CompensatorService, AJumpAheadIsFollowedOnceConfirmed) {
  Harness h;
  h.run(0, 1000);
  h.run(5000, 30);
  EXPECT_EQ(h.service.sequence_counters().jumps, 1u);
  EXPECT_EQ(h.service.compensator().last_seq(), 5029);
  EXPECT_EQ(h.sent_through(), 5029 + kHorizon);
  EXPECT_EQ(h.service.counters().bridge_restarts, 0u);
}

trajectory_t hold(std::int32_t version, double offset_m, double blend_s = 0.0, std::int64_t start_utime = 0) {
  trajectory_t t{};
  t.version = version;
  t.shape = trajectory_t::HOLD;
  t.offset_m = offset_m;
  t.blend_s = blend_s;
  t.start_utime = start_utime;
  return t;
}

// Checked inline (compensator.trajectory_check: inline, as the golden replay runs), a trajectory
// takes effect in the handler of its own message, at the first tick not yet sent: where the
// message came among the sensor blocks decides it, never how long a thread took.
TEST(CompensatorService, ATrajectoryCheckedInlineTakesEffectAtOnce) {
  CompensatorSettings s = cosine();
  s.check_on_thread = false;
  Harness h(s);
  h.send(0);  // planned through 309
  h.service.on_trajectory(hold(1, 2e-7));
  EXPECT_EQ(h.service.counters().trajectories, 1u);  // no settle_trajectories(): nothing was left to a thread
  h.send(10);
  EXPECT_LT(h.tick(309).y_ref_m, 0.0);
  EXPECT_EQ(h.tick(310).y_ref_m, 2e-7);
  EXPECT_FALSE(
      load_compensator_settings(Config::from_string("compensator: {trajectory_check: inline}\n")).check_on_thread);
  EXPECT_TRUE(load_compensator_settings(Config()).check_on_thread);
  EXPECT_THROW(load_compensator_settings(Config::from_string("compensator: {trajectory_check: later}\n")), ConfigError);
}

TEST(CompensatorService, AppliesATrajectoryVersionOnceFromTheFirstTickNotSentAndRefusesABadOne) {
  Harness h;
  h.send(0);  // planned through 309
  h.service.on_trajectory(hold(1, 2e-7));
  h.service.settle_trajectories();
  h.service.on_trajectory(hold(1, 2e-7));
  h.service.settle_trajectories();
  EXPECT_EQ(h.service.counters().trajectory_repeats, 1u);
  trajectory_t bad = hold(2, 0.0);
  bad.shape = trajectory_t::POINTS;  // POINTS without points
  h.service.on_trajectory(bad);
  h.service.settle_trajectories();
  EXPECT_EQ(h.service.counters().trajectory_refused, 1u);
  h.service.on_trajectory(hold(1, 2e-7));  // v1 is still the one in force
  h.service.settle_trajectories();
  EXPECT_EQ(h.service.counters().trajectory_repeats, 2u);
  EXPECT_EQ(h.service.counters().trajectories, 1u);

  h.send(10);
  EXPECT_LT(h.tick(309).y_ref_m, 0.0);  // sent before: still the cosine's approach
  for (std::int64_t k = 310; k < 320; ++k) EXPECT_EQ(h.tick(k).y_ref_m, 2e-7) << k;  // no blend: at once
  h.run(20, 2000);
  EXPECT_EQ(h.tick(h.sent_through()).y_ref_m, 2e-7);

  // With a blend, from where the reference was, monotone over blend_s.
  const std::int64_t first = h.sent_through() + 1;
  h.service.on_trajectory(hold(4, -3e-7, 0.01));
  h.service.settle_trajectories();
  h.run(2020, 200);
  EXPECT_EQ(h.tick(first).y_ref_m, 2e-7);
  for (std::int64_t k = first + 1; k <= first + 100; ++k) EXPECT_LT(h.tick(k).y_ref_m, h.tick(k - 1).y_ref_m) << k;
  EXPECT_NEAR(h.tick(first + 100).y_ref_m, -3e-7, 1e-15);
  EXPECT_EQ(h.tick(first + 101).y_ref_m, -3e-7);
  EXPECT_EQ(h.service.counters().trajectories, 2u);
}

// The dry runs deciding a trajectory run off the I/O thread: a refusal searching for the largest
// feasible amplitude of a 1 Hz line took 65 ms on a busy machine, longer than the bridge's buffer,
// and its watchdog took the stage to the safe state. The plan goes on under the trajectory in
// force while the check runs; its verdict is taken at a sensor block after the check ends.
TEST(CompensatorService, ATrajectoryIsCheckedWhileThePlanGoesOn) {
  CompensatorSettings s = cosine();
  const CompensatorConfig real = deployed().control;  // the actuator's limits, which refuse 1 mm
  s.control.u_min_V = real.u_min_V;
  s.control.u_max_V = real.u_max_V;
  s.control.slew_V_per_s = real.slew_V_per_s;
  s.control.slew_fraction = real.slew_fraction;
  Harness h(s);
  h.send(0);  // planned through 309
  trajectory_t huge = hold(7, 0.0);
  huge.shape = trajectory_t::SINE;
  huge.amplitude_m = 1e-3;  // far beyond the actuator's range
  huge.frequency_Hz = 1.0;
  h.service.on_trajectory(huge);
  EXPECT_EQ(h.service.counters().trajectory_refused, 0u);  // not decided in the handler
  h.service.on_trajectory(huge);                           // a UDP repeat while it is checked
  EXPECT_EQ(h.service.counters().trajectory_repeats, 1u);
  h.send(10);  // planned on under the cosine in force
  EXPECT_LT(h.tick(319).y_ref_m, 0.0);
  h.service.settle_trajectories();
  EXPECT_EQ(h.service.counters().trajectory_refused, 1u);
  EXPECT_EQ(h.service.counters().trajectories, 0u);
  EXPECT_EQ(h.service.counters().trajectory_refused_version, 7);
  EXPECT_EQ(h.service.compensator().counters().plan_refusals, 1u);
  // The next one is checked and taken.
  h.service.on_trajectory(hold(8, 2e-7, 0.05));
  h.service.settle_trajectories();
  EXPECT_EQ(h.service.counters().trajectories, 1u);
  h.run(20, 1000);
  EXPECT_EQ(h.tick(h.sent_through()).y_ref_m, 2e-7);
  // The plan's refusal is on HX_STATUS under its own name, as every counter of the plan is.
  std::map<std::string, std::int64_t> reported = report_status(h).counters;
  EXPECT_EQ(reported["plan_refusals"], 1);
  EXPECT_EQ(reported["trajectory_refused"], 1);
  CompensatorCounters::for_each([&](const char* name, auto) { EXPECT_TRUE(reported.contains(name)) << name; });
}

// A line whose learning makes its error worse (the plant's sign the opposite of the model's) is
// stopped by the monitor: the status is DEGRADED, says why, and counts it.
TEST(CompensatorService, ALineWhoseLearningTheMonitorStoppedIsDegradedWithTheReason) {
  CompensatorSettings s = holding();
  s.trajectory.shape = TrajectoryShape::kSine;
  s.trajectory.amplitude_m = 1e-7;
  s.trajectory.frequency_hz = 100.0;
  s.trajectory.blend_s = 0.01;
  s.control.learning.monitor_ratio = 1.05;
  Harness h(s);
  h.plant_gain = -kGain;
  h.run(0, 5000);
  const Reported r = report_status(h);
  const service_status_t& st = r.status;
  EXPECT_EQ(h.service.compensator().learner().figures().divergences, 1u);
  EXPECT_EQ(st.state, service_status_t::DEGRADED) << st.detail;
  EXPECT_NE(st.detail.find("learning stopped: it made the line's error worse than without"), std::string::npos)
      << st.detail;
  std::map<std::string, std::int64_t> reported = r.counters;
  EXPECT_EQ(reported["learning_divergences"], 1);
  EXPECT_EQ(reported["learning_active"], 0);
}

// 100 forged sensor blocks and refused trajectories a second made ~95 log lines a second of one
// reason and 488 status reports in 5 s: each verdict sent a report at once, and each report
// logged the jumps not believed. An extra report now goes out at most every 100 ms (what asked
// for one meanwhile is in the next), and the sequence lines go through the limiter.
TEST(CompensatorService, AFloodOfForgedBlocksAndRefusedTrajectoriesIsReportedAndLoggedAtABoundedRate) {
  auto out = std::make_shared<std::ostringstream>();
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(*out);
  const auto previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>("capture", sink));
  double elapsed_s = 0.0;
  std::uint64_t reports = 0;
  {
    Harness h;
    Subscription<service_status_t> status(*h.lcm, h.channels.status);
    h.send(0);
    const double start_s = monotonic_s();
    double periodic_s = start_s;
    std::int64_t seq = 10;
    std::int32_t version = 2;
    while (monotonic_s() - start_s < 1.5) {
      h.send(seq + 900);  // forged: far ahead, never confirmed
      trajectory_t bad = hold(version++, 0.0);
      bad.shape = trajectory_t::POINTS;  // POINTS without points: refused
      h.service.on_trajectory(bad);
      h.service.settle_trajectories();
      h.send(seq);
      seq += 10;
      if (monotonic_s() - periodic_s >= 1.0) {  // as the I/O loop does
        h.service.report(wall_utime(), false);
        periodic_s = monotonic_s();
      }
      h.drain();
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    elapsed_s = monotonic_s() - start_s;
    EXPECT_GE(h.service.counters().trajectory_refused, 50u);
    EXPECT_GE(h.service.sequence_counters().ignored, 50u);
    reports = status.counters().received;
  }
  spdlog::set_default_logger(previous);
  // At most one extra report per 100 ms and the periodic one a second (+1: the first is at once).
  EXPECT_LE(static_cast<double>(reports), elapsed_s / 0.1 + elapsed_s + 1.0);
  EXPECT_GE(reports, 5u);  // verdicts are still answered
  const std::string log = out->str();
  std::size_t not_believed = 0, lines = 0;
  for (std::size_t at = 0; (at = log.find("not believed", at)) != std::string::npos; ++at) ++not_believed;
  for (const char c : log) lines += c == '\n';
  EXPECT_LE(not_believed, 2u) << log.substr(0, 3000);  // one a second
  EXPECT_LE(lines, 8u) << log.substr(0, 3000);
}

// The reference of tick k for a hold at 1e-7 starting at tick 1000, approached from 0 over 10 ms.
double approach_to_1e7(std::int64_t k) {
  const double into = static_cast<double>(k) * kDt - 0.09;
  if (into <= 0.0) return 0.0;
  if (into >= 0.01) return 1e-7;
  return 1e-7 * (0.5 - 0.5 * std::cos(std::numbers::pi * into / 0.01));
}

void expect_starts_at_tick_1000(const Harness& h) {
  for (std::int64_t k = 310; k < 900; ++k) ASSERT_EQ(h.tick(k).y_ref_m, 0.0) << k;
  for (std::int64_t k = 900; k <= 1000; ++k) EXPECT_NEAR(h.tick(k).y_ref_m, approach_to_1e7(k), 1e-13) << k;
  EXPECT_GT(h.tick(950).y_ref_m, 4e-8);
  EXPECT_LT(h.tick(950).y_ref_m, 6e-8);
  for (std::int64_t k = 1001; k < 1100; ++k) ASSERT_EQ(h.tick(k).y_ref_m, 1e-7) << k;
}

TEST(CompensatorService, ATimedTrajectoryStartsAtItsLoopTime) {
  Harness h(holding());  // holding at 0
  h.send(0);
  // Tick 1000's wall time on the bridge's clock (taken from the samples' utime): approach over
  // ticks 900..1000.
  h.service.on_trajectory(hold(5, 1e-7, 0.01, utime_of(1000)));
  h.service.settle_trajectories();
  h.run(10, 1100);
  expect_starts_at_tick_1000(h);
  EXPECT_EQ(h.service.counters().trajectory_late_start, 0u);
  h.service.on_trajectory(hold(6, 1e-7, 0.01, utime_of(100)));  // already past: started now, counted
  h.service.settle_trajectories();
  EXPECT_EQ(h.service.counters().trajectory_late_start, 1u);
  EXPECT_EQ(h.service.counters().trajectories, 2u);
}

TEST(CompensatorService, ATimedTrajectoryBeforeTheFirstSampleWaitsForItsLoopTime) {
  Harness h(holding());
  h.service.on_trajectory(hold(5, 1e-7, 0.01, utime_of(1000)));
  h.service.settle_trajectories();
  EXPECT_EQ(h.service.counters().trajectories, 0u);  // waits for a sample to map its start time
  h.run(0, 1110);
  EXPECT_EQ(h.service.counters().trajectories, 1u);
  expect_starts_at_tick_1000(h);
}

// A newer trajectory replaces one still waiting for the first sample.
TEST(CompensatorService, ANewerTrajectoryReplacesOneWaitingForTheFirstSample) {
  Harness h(holding());
  h.service.on_trajectory(hold(5, 1e-7, 0.01, utime_of(1000)));
  h.service.settle_trajectories();
  h.service.on_trajectory(hold(6, 3e-7));  // untimed, newer: in force from the first tick planned
  h.service.settle_trajectories();
  h.run(0, 1200);
  EXPECT_EQ(h.tick(10).y_ref_m, 3e-7);
  EXPECT_EQ(h.tick(1100).y_ref_m, 3e-7);
}

TEST(CompensatorService, ControlRequests) {
  Harness h(holding());
  h.send(0);  // planned through 309
  control_t c = request(1, control_t::SET_MODE);
  c.mode = command_block_t::MODE_PI;
  h.service.on_control(c);
  EXPECT_EQ(h.service.compensator().mode(), FeedforwardMode::kPi);
  h.service.on_control(c);  // a repeat of request 1: acted on once
  EXPECT_EQ(h.service.counters().control_acted, 1u);
  h.send(10);
  EXPECT_EQ(h.tick(309).mode, command_block_t::MODE_MEM);  // sent before the request
  EXPECT_EQ(h.tick(310).mode, command_block_t::MODE_PI);

  c = request(2, control_t::SET_MODE);
  c.mode = command_block_t::MODE_EXPERIMENT;  // started, not selected
  h.service.on_control(c);
  c = request(3, control_t::SET_MODE);
  c.mode = 9;
  h.service.on_control(c);
  EXPECT_EQ(h.service.counters().control_refused, 2u);
  EXPECT_EQ(h.service.compensator().mode(), FeedforwardMode::kPi);

  c = request(4, control_t::START_EXPERIMENT);
  c.experiment = "sine";
  c.experiment_amplitude_V = 100.0;
  c.experiment_frequency_Hz = 10.0;
  c.experiment_duration_s = 0.1;
  h.service.on_control(c);
  EXPECT_TRUE(h.service.compensator().experiment_running());
  h.run(20, 210);  // ticks 320..529: the experiment
  for (std::int64_t k = 320; k < 530; ++k) {
    ASSERT_EQ(h.tick(k).mode, command_block_t::MODE_EXPERIMENT) << k;
    ASSERT_TRUE(std::isnan(h.tick(k).y_ref_m)) << k;
    ASSERT_LE(std::abs(h.tick(k).u_ff_V), 100.0) << k;
  }
  for (std::int64_t k = 320; k < 530; ++k) {  // started at the first tick not sent
    EXPECT_NEAR(h.tick(k).u_ff_V, 100.0 * std::sin(2.0 * std::numbers::pi * 10.0 * static_cast<double>(k - 320) * kDt),
                1e-9)
        << k;
  }

  h.service.on_control(request(5, control_t::STOP_EXPERIMENT));  // ends at the first tick not sent (530)
  h.send(230);
  EXPECT_FALSE(h.service.compensator().experiment_running());
  // Then the last voltage is held, without a reference, until the sample of tick 530 arrives;
  // from there the reference approaches again from where the stage is.
  h.run(240, 600);
  const double held = h.tick(529).u_ff_V;
  std::int64_t tracking = 530;
  while (std::isnan(h.tick(tracking).y_ref_m)) {
    ASSERT_EQ(h.tick(tracking).u_ff_V, held) << tracking;
    ASSERT_EQ(h.tick(tracking).mode, command_block_t::MODE_PI) << tracking;
    ++tracking;
  }
  EXPECT_GT(tracking, 539);                 // not before the sample of tick 530 (in the block 530..539)
  EXPECT_LE(tracking, 539 + kHorizon + 1);  // planned with the answer to that block
  for (std::int64_t k = tracking; k <= h.sent_through(); ++k) ASSERT_TRUE(std::isfinite(h.tick(k).y_ref_m)) << k;

  h.service.on_control(request(6, control_t::ARM, "compensator"));  // the bridge's, addressed to us
  EXPECT_EQ(h.service.counters().control_refused, 3u);
  control_t gains = request(7, control_t::SET_GAINS, "compensator");  // the servo is the bridge's now
  gains.kp = 0.2;
  gains.ki = 300.0;
  h.service.on_control(gains);
  EXPECT_EQ(h.service.counters().control_refused, 4u);
  for (const char* target : {"", "bridge"}) {  // to everyone, or the bridge's: not ours, not an error
    gains.request_id += 1;
    gains.target = target;
    h.service.on_control(gains);
  }
  h.service.on_control(request(10, control_t::DISARM));
  EXPECT_EQ(h.service.counters().control_refused, 4u);
  EXPECT_EQ(h.service.counters().control_acted, 3u);  // SET_MODE, START_EXPERIMENT, STOP_EXPERIMENT
  h.service.on_control(request(11, control_t::RESET_COUNTERS));
  EXPECT_EQ(h.service.counters().control_acted, 4u);
}

TEST(CompensatorService, RestartsTheControlLawWhenTheBridgeRestarts) {
  Harness h;
  h.run(50000, 100);
  control_t c = request(1, control_t::SET_MODE);
  c.mode = command_block_t::MODE_PI;
  h.service.on_control(c);
  const std::size_t b = h.blocks.size();
  h.send(0);
  h.send(10);
  EXPECT_EQ(h.blocks.size(), b);  // seq went back by far more than a reorder: held until confirmed
  EXPECT_EQ(h.service.counters().bridge_restarts, 0u);
  h.run(20, 80);  // the third block of the new numbering confirms it: a new bridge
  EXPECT_EQ(h.service.counters().bridge_restarts, 1u);
  EXPECT_EQ(h.service.sequence_counters().held, 2u);
  EXPECT_EQ(h.service.compensator().counters().out_of_order, 0u);
  EXPECT_EQ(h.service.compensator().last_seq(), 99);
  // The new clock's ticks, from the confirming block's on, each once.
  ASSERT_LT(b, h.blocks.size());
  EXPECT_EQ(h.blocks[b].seq, 30);
  EXPECT_EQ(h.blocks[b].n_ticks, kHorizon);
  EXPECT_EQ(h.blocks[b].sample_seq, 29);
  std::int64_t next = 30;
  for (std::size_t i = b; i < h.blocks.size(); ++i) {
    EXPECT_EQ(h.blocks[i].seq, next) << i;
    next += h.blocks[i].n_ticks;
  }
  EXPECT_EQ(h.sent_through(), 99 + kHorizon);
  // The mode in force is kept; the reference restarts from 0.
  EXPECT_EQ(h.tick(30).mode, command_block_t::MODE_PI);
  EXPECT_EQ(h.tick(30).y_ref_m, 0.0);
  EXPECT_LT(h.tick(300).y_ref_m, 0.0);
}

// What produced a tick's u_ff is labelled with that set's version, also after a restart.
TEST(CompensatorService, ABridgeRestartKeepsTheParameterSetInUseAndItsVersion) {
  Harness h;
  h.send(50000);
  h.service.on_params(params(2, 5.5e-9));
  h.run(50010, 990);  // past the reversal near tick 50510
  ASSERT_EQ(h.service.compensator().params_version(), 2);
  const std::size_t from = h.ticks.size();
  h.run(0, 100);
  ASSERT_EQ(h.service.counters().bridge_restarts, 1u);
  EXPECT_EQ(h.service.compensator().mem_params().c1, 5.5e-9);
  EXPECT_EQ(h.service.compensator().params_version(), 2);
  ASSERT_LT(from, h.ticks.size());
  EXPECT_EQ(h.ticks[from].params_version, 2);
  EXPECT_EQ(h.ticks.back().params_version, 2);
}

TEST(CompensatorService, AParameterSetWaitingForAReversalSurvivesABridgeRestart) {
  Harness h;
  h.run(50000, 100);
  h.service.on_params(params(2, 5.5e-9));  // accepted; its reversal (near 50510) is not planned yet
  h.run(0, 1000);                          // restarted: the new reference's reversal is near tick 510
  ASSERT_EQ(h.service.counters().bridge_restarts, 1u);
  EXPECT_EQ(h.service.compensator().params_version(), 2);
  EXPECT_EQ(h.service.compensator().mem_params().c1, 5.5e-9);
}

// Blocks under one numbering, then a bridge restart's, then one HX_STATUS report: its counters by name.
std::map<std::string, std::int64_t> status_after_a_restart(Harness& h) {
  h.run(50000, 100);
  h.run(0, 100);
  return report_status(h).counters;
}

// HX_STATUS counters only count up (CounterSet): a bridge restart replaces the control law but
// not what it counted.
TEST(CompensatorService, StatusCountersKeepCountingAcrossABridgeRestart) {
  Harness h;
  const std::map<std::string, std::int64_t> value = status_after_a_restart(h);
  EXPECT_EQ(value.at("bridge_restarts"), 1);
  EXPECT_EQ(value.at("sensor_blocks_held"), 2);  // the new numbering's first two, before the third confirmed it
  EXPECT_EQ(value.at("sensor_jumps_ignored"), 0);
  EXPECT_EQ(value.at("command_ticks_published"), static_cast<std::int64_t>(h.ticks.size()));
  EXPECT_EQ(value.at("samples"), 180);
  EXPECT_EQ(value.at("planned"), static_cast<std::int64_t>(h.ticks.size()));
}

// The summary file carries every counter HX_STATUS does, under the same name and over the whole
// run: a bridge restart's retired control law still counts (it once wrote the last law's alone).
TEST(CompensatorService, TheSummaryFileHasTheStatusCountersOverTheWholeRun) {
  Harness h;
  const std::map<std::string, std::int64_t> reported = status_after_a_restart(h);
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("compensator_summary_" + std::to_string(::getpid()) + ".json");
  h.service.write_summary_to(path.string());
  h.service.write_summary_json();
  std::ifstream in(path);
  const nlohmann::json summary = nlohmann::json::parse(in);
  std::filesystem::remove(path);
  std::size_t counters = 0;
  for (const auto& [name, value] : summary.items()) {
    if (name == "block_to_answer_us") continue;
    ++counters;
    ASSERT_TRUE(reported.contains(name)) << name << " is in the summary, not on HX_STATUS";
    EXPECT_EQ(value.get<std::int64_t>(), reported.at(name)) << name;
  }
  EXPECT_GE(counters, 30u);
  for (const char* name : {"command_ticks_published", "ticks_behind", "params_rejected", "sensor_blocks_held"}) {
    EXPECT_TRUE(summary.contains(name)) << name;
  }
  EXPECT_EQ(summary["samples"], 180);
  EXPECT_EQ(summary["bridge_restarts"], 1);
  EXPECT_TRUE(summary.contains("block_to_answer_us"));
}

std::string settings_refusal(const std::string& yaml) {
  try {
    load_compensator_settings(Config::from_string(yaml, "compensator.yaml"));
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "accepted";
}

using testing::contains;

TEST(CompensatorSettings, RefusedOldKeysSayWhereTheyWent) {
  const std::string lead = settings_refusal("compensator: {mode: mem, lead_ticks: 2}");
  EXPECT_TRUE(contains(lead, "compensator.yaml: compensator.lead_ticks")) << lead;
  EXPECT_TRUE(contains(lead, "compensator.horizon_s")) << lead;
  for (const char* key : {"kp", "ki", "kd"}) {
    const std::string why = settings_refusal(std::string("feedback: {") + key + ": 0.1}");
    EXPECT_TRUE(contains(why, std::string("compensator.yaml: feedback.") + key)) << why;
    EXPECT_TRUE(contains(why, "servo.kp")) << why;
    EXPECT_TRUE(contains(why, "bridge")) << why;
  }
}

TEST(CompensatorSettings, TheHorizonIsGivenInSecondsAndPlannedInTicks) {
  const auto ticks_in = [](const std::string& file) {
    const Config c = Config::load_file(kConfigDir + file);
    return std::llround(c.get<double>("compensator.horizon_s") / c.get<double>("compensator.dt_s", 1e-4));
  };
  const CompensatorSettings deploy = deployed();
  EXPECT_EQ(deploy.control.horizon_ticks, ticks_in("compensator.yaml"));
  const auto load = [](const std::string& yaml) {
    return load_compensator_settings(Config::from_string(yaml, "compensator.yaml")).control;
  };
  EXPECT_EQ(load("compensator: {horizon_s: 0.25}").horizon_ticks, 2500);
  EXPECT_EQ(load("compensator: {horizon_s: 0.03, dt_s: 2.0e-4}").horizon_ticks, 150);
  EXPECT_TRUE(
      contains(settings_refusal("compensator: {horizon_s: 0.0001}"), "compensator.yaml: compensator.horizon_s"));
  EXPECT_TRUE(contains(settings_refusal("compensator: {horizon_s: 1.0}"), "compensator.yaml: compensator.horizon_s"));
  const CompensatorSettings demo = load_compensator_settings(Config::load_file(kConfigDir + "demo/compensator.yaml"));
  EXPECT_EQ(demo.control.horizon_ticks, ticks_in("demo/compensator.yaml"));
  const auto lines = describe(deploy);
  const std::string plans = "plans " + std::to_string(deploy.control.horizon_ticks) + " ticks";
  EXPECT_TRUE(std::any_of(lines.begin(), lines.end(), [&](const std::string& l) { return contains(l, plans); }));
}

TEST(TrajectoryMessage, MapsWallTimeToLoopTime) {
  EXPECT_DOUBLE_EQ(loop_time_of_utime(2'000'500, 2'000'000, 1000, 1e-4), 0.1 + 0.0005);
  trajectory_t t{};
  t.version = 1;
  t.shape = 9;
  EXPECT_THROW(trajectory_from_message(t), ParameterError);
}

}  // namespace
}  // namespace hystloop

namespace hystloop {
namespace {

TEST(CompensatorSettings, TheStageTheLearningAndTheActuatorComeFromTheConfig) {
  const CompensatorSettings deploy = deployed();
  EXPECT_TRUE(deploy.control.stage.has_dynamics());  // the simulated stage's Table 2
  EXPECT_DOUBLE_EQ(deploy.control.stage.second_order.k, 1.17e8);
  EXPECT_DOUBLE_EQ(deploy.control.stage.second_order.c, 2.03e3);
  EXPECT_TRUE(deploy.control.learning.enabled);
  EXPECT_TRUE(deploy.control.learning.lag_compensated);
  EXPECT_EQ(deploy.control.slew_V_per_s, 5.0e4);
  EXPECT_EQ(deploy.control.mode, FeedforwardMode::kPi);
  EXPECT_TRUE(contains(settings_refusal("stage: {kind: third_order}"), "stage.kind"));
  EXPECT_TRUE(contains(settings_refusal("stage: {kind: second_order, c: 1.0e-3}"), "sampling zero"));
  EXPECT_TRUE(contains(settings_refusal("stage: {k: 1.0e8}"), "stage.kind"));  // k without a stage
  EXPECT_TRUE(contains(settings_refusal("stage: {kind: second_order, order: backwards}"), "stage.order"));
  EXPECT_TRUE(contains(settings_refusal("learning: {gain: 2.0}"), "learning.gain"));
  EXPECT_TRUE(contains(settings_refusal("actuator: {slew_V_per_s: -1}"), "actuator.slew_V_per_s"));
  EXPECT_TRUE(contains(settings_refusal("compensator: {plan_slew_fraction: 0}"), "compensator.plan_slew_fraction"));
  const auto none = load_compensator_settings(Config::from_string("stage: {kind: none}", "compensator.yaml"));
  EXPECT_FALSE(none.control.stage.has_dynamics());
}

// A linear stage of any order with delay, in the forms the bridge's plant takes: read, inverted
// with the preview it needs, and refused naming the key.
TEST(CompensatorSettings, ALinearStageIsReadInEveryFormAndRefusedByItsKey) {
  const auto two_modes = load_compensator_settings(Config::from_string(
      "stage: {kind: linear, delay_s: 1.5e-4, modes: [{frequency_hz: 780, damping_ratio: 0.03, weight: 0.92}, "
      "{frequency_hz: 2400, damping_ratio: 0.02, weight: 0.08}]}",
      "compensator.yaml"));
  ASSERT_TRUE(two_modes.control.stage.is_linear());
  EXPECT_EQ(two_modes.control.stage.linear.order(), 4);
  EXPECT_DOUBLE_EQ(two_modes.control.stage.linear.delay_s, 1.5e-4);
  const auto zpk = load_compensator_settings(Config::from_string(
      "stage: {kind: linear, poles_hz: [[-23.4, 779.6], [-48, 2400]], zeros_hz: [[3000, 0]]}", "compensator.yaml"));
  EXPECT_EQ(zpk.control.stage.linear.order(), 4);
  EXPECT_TRUE(contains(settings_refusal("stage: {kind: linear}"), "stage.modes"));
  EXPECT_TRUE(contains(settings_refusal("stage: {kind: linear, poles_hz: [[10, 100]]}"), "stage.poles"));  // unstable
  EXPECT_TRUE(contains(settings_refusal("stage: {kind: linear, modes: [{frequency_hz: 780, damping_ratio: 0.03}], "
                                        "k: 1.0e8}"),
                       "stage.k"));
  EXPECT_TRUE(contains(settings_refusal("stage: {kind: second_order, delay_s: 1.0e-4}"), "stage.delay_s"));
  EXPECT_TRUE(contains(settings_refusal("stage: {kind: linear, preview_ticks: 1, delay_s: 1.5e-4, modes: "
                                        "[{frequency_hz: 780, damping_ratio: 0.03}]}"),
                       "stage.preview_ticks"));
  // How far up its identification measured it: read for a linear stage, within Nyquist, and only there.
  const auto known = load_compensator_settings(
      Config::from_string("stage: {kind: linear, known_to_hz: 1220, modes: [{frequency_hz: 780, damping_ratio: 0.03}]}",
                          "compensator.yaml"));
  EXPECT_EQ(known.control.stage.known_to_hz, 1220.0);
  EXPECT_TRUE(contains(settings_refusal("stage: {kind: linear, known_to_hz: 6000, modes: "
                                        "[{frequency_hz: 780, damping_ratio: 0.03}]}"),
                       "stage.known_to_hz"));
  EXPECT_TRUE(contains(settings_refusal("stage: {kind: second_order, known_to_hz: 1000}"), "stage.known_to_hz"));
}

}  // namespace
}  // namespace hystloop

namespace hystloop {
namespace {

TEST(CompensatorSettings, TheBanningFitsStageIsTakenWithParams) {
  // hystloop-identify --model banning --out FILE writes the bridge's banning section and the
  // compensator's stage section: --params FILE takes the latter, leaves the former.
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "hystloop-banning-params.yaml";
  {
    std::ofstream out(file);
    out << "banning:\n  hysteresis: {a: 8.6e-9, b: 6.1e-9, alpha: 0.0123, s_max: 750}\n  stage: {k: 1.2e8, c: 2.1e3}\n"
        << "stage:\n  kind: second_order\n  k: 1.2e8\n  c: 2.1e3\n  order: hysteresis_then_stage\n";
  }
  Config config = Config::from_string("compensator: {mode: pi}", "compensator.yaml");
  merge_params_file(config, file);
  const CompensatorSettings s = load_compensator_settings(config);
  EXPECT_TRUE(s.control.stage.has_dynamics());
  EXPECT_DOUBLE_EQ(s.control.stage.second_order.k, 1.2e8);
  EXPECT_DOUBLE_EQ(s.control.stage.second_order.c, 2.1e3);
  std::filesystem::remove(file);
}

}  // namespace
}  // namespace hystloop
