// bridge.backend: comedi driving several axes (x, y, z), a channel pair each, against the fake
// card (tests/hw/fake_comedi.hpp): the comedi.y.* / comedi.z.* keys and their refusals; one
// instruction list per tick carrying every axis's write, then every axis's read; each axis its
// own clamp, conversions, faults and safe voltage; a refusal after opening leaving every usable
// output safe; the probe on one axis with the others held; and the bridge's real-time thread
// taking every axis to its safe voltage (a stop, a failing sensor on one axis).
#include "bridge/comedi_backend.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "bridge/bridge_realtime.hpp"
#include "bridge/bridge_settings.hpp"
#include "bridge/probe_hardware.hpp"
#include "fake_comedi.hpp"
#include "support/allocation_counter.hpp"
#include "support/refusal.hpp"
#include "support/text.hpp"

namespace hystloop {
namespace {

using fake_comedi::kMaxdata;

using testing::contains;

std::string refusal(const std::string& yaml) {
  return testing::config_refusal([&] { load_bridge_settings(Config::from_string(yaml, "bridge.yaml")); });
}

BridgeSettings load(const std::string& yaml) { return load_bridge_settings(Config::from_string(yaml, "bridge.yaml")); }

// comedilib's range-table conversions (comedi_from_phys / comedi_to_phys).
lsampl_t code(double V, double lo, double hi) {
  return static_cast<lsampl_t>(std::floor((V - lo) / (hi - lo) * kMaxdata + 0.5));
}
double volts(lsampl_t counts, double lo, double hi) { return lo + (hi - lo) * counts / double(kMaxdata); }

const std::string kCard = "bridge: {backend: comedi, axes: 2}\nrt: {ticks_per_wake: 1, required: false}\n";

// ---- the keys ----

TEST(ComediAxesConfig, TwoAndThreeAxisConfigsLoadEachKeyDefaultingToAxisXs) {
  const BridgeSettings two = load(kCard +
                                  "comedi: {ao: {range: 0}, ai: {channel: 2, range: 1, aref: diff}, "
                                  "amplifier_gain_V_per_V: 20.0, sensor: {scale_m_per_V: 2.0e-7, offset_m: 1.0e-6},\n"
                                  "  y: {ao: {channel: 1}, ai: {channel: 3}, sensor: {scale_m_per_V: -1.0e-7}}}");
  EXPECT_EQ(two.comedi.axes, 2);
  const ComediAxisSettings& y = two.comedi.axis(1);
  EXPECT_EQ(y.ao.channel, 1);
  EXPECT_EQ(y.ai.channel, 3);
  EXPECT_EQ(y.ai.range, 1);  // the rest as x's
  EXPECT_EQ(y.ai.aref, AREF_DIFF);
  EXPECT_EQ(y.ao.subdevice, -1);
  EXPECT_EQ(y.amplifier_gain_V_per_V, 20.0);
  EXPECT_EQ(y.sensor_offset_m, 1e-6);
  EXPECT_EQ(y.sensor_scale_m_per_V, -1e-7);  // its own
  EXPECT_EQ(two.comedi.axis(0).ai.channel, 2);
  EXPECT_EQ(two.comedi.ai.channel, 2);  // axis x's are the settings' own: one-axis code reads them

  const BridgeSettings three = load(
      "bridge: {backend: comedi, axes: 3}\nrt: {ticks_per_wake: 1, required: false}\n"
      "comedi:\n  y: {ao: {channel: 1}, ai: {channel: 1}}\n"
      "  z: {ao: {subdevice: 1, channel: 2, range: 1, aref: ground}, ai: {subdevice: 0, channel: 7, range: 2, aref: "
      "common}, amplifier_gain_V_per_V: 50.0, sensor: {scale_m_per_V: 5.0e-8, offset_m: -2.0e-6}}\n"
      "actuator: {z: {u_min_V: 0.0, u_max_V: 400.0, safe_u_V: 0.0}}");
  EXPECT_EQ(three.comedi.axes, 3);
  const ComediAxisSettings& z = three.comedi.axis(2);
  EXPECT_EQ(z.ao.subdevice, 1);
  EXPECT_EQ(z.ao.channel, 2);
  EXPECT_EQ(z.ao.range, 1);
  EXPECT_EQ(z.ai.subdevice, 0);
  EXPECT_EQ(z.ai.channel, 7);
  EXPECT_EQ(z.ai.range, 2);
  EXPECT_EQ(z.ai.aref, AREF_COMMON);
  EXPECT_EQ(z.amplifier_gain_V_per_V, 50.0);
  EXPECT_EQ(z.sensor_scale_m_per_V, 5e-8);
  EXPECT_EQ(z.sensor_offset_m, -2e-6);
  EXPECT_DOUBLE_EQ(z.card_V(400.0), 8.0);
  // The start-up log: the card's line, the enable's, then one per axis.
  const std::vector<std::string> lines = describe(three.comedi);
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_TRUE(contains(lines[1], "no amplifier enable line")) << lines[1];
  EXPECT_TRUE(contains(lines[4], "comedi z: ao subdevice 1 channel 2 range 1")) << lines[4];
  std::size_t comedi_lines = 0;
  for (const std::string& l : describe(three)) comedi_lines += l.starts_with("comedi") ? 1 : 0;
  EXPECT_EQ(comedi_lines, 5u);
  // A one-axis config is unchanged, and a simulator with several axes needs no comedi.y keys.
  EXPECT_EQ(load("bridge: {backend: comedi}\nrt: {required: false}\n").comedi.axes, 1);
  EXPECT_EQ(refusal("bridge: {backend: sim, axes: 3}"), "accepted");
}

TEST(ComediAxesConfig, AChannelOfAnotherAxisMustBeGivenAndIsRefusedByItsKey) {
  EXPECT_TRUE(contains(refusal(kCard), "bridge.yaml: comedi.y.ao.channel: must be given for axis y")) << refusal(kCard);
  EXPECT_TRUE(contains(refusal(kCard + "comedi: {y: {ao: {channel: 1}}}"), "bridge.yaml: comedi.y.ai.channel"));
  EXPECT_TRUE(contains(refusal(kCard + "comedi: {y: {ai: {channel: 1}}}"), "bridge.yaml: comedi.y.ao.channel"));
  // Other keys of its own do not stand in for the channel.
  EXPECT_TRUE(contains(refusal(kCard + "comedi: {y: {ao: {range: 0}, ai: {channel: 1}}}"), "comedi.y.ao.channel"));
  const std::string three =
      "bridge: {backend: comedi, axes: 3}\nrt: {required: false}\ncomedi: {y: {ao: {channel: 1}, ai: {channel: 1}}";
  EXPECT_TRUE(contains(refusal(three + "}"), "bridge.yaml: comedi.z.ao.channel"));
  EXPECT_EQ(refusal(three + ", z: {ao: {channel: 2}, ai: {channel: 2}}}"), "accepted");
  // Their values are validated as axis x's are.
  EXPECT_TRUE(contains(refusal(kCard + "comedi: {y: {ao: {channel: -1}, ai: {channel: 1}}}"), "comedi.y.ao.channel"));
  EXPECT_TRUE(contains(refusal(kCard + "comedi: {y: {ao: {channel: 1}, ai: {channel: 1, aref: floating}}}"),
                       "bridge.yaml: comedi.y.ai.aref"));
  EXPECT_TRUE(contains(refusal(kCard + "comedi: {y: {ao: {channel: 1}, ai: {channel: 1}, sensor: {scale_m_per_V: 0}}}"),
                       "bridge.yaml: comedi.y.sensor.scale_m_per_V"));
  EXPECT_TRUE(contains(refusal(kCard + "comedi: {y: {ao: {channel: 1}, ai: {channel: 1}, amplifier_gain_V_per_V: 0}}"),
                       "bridge.yaml: comedi.y.amplifier_gain_V_per_V"));
  // ... also for a simulator (one config serves both), which needs no channels.
  EXPECT_TRUE(contains(refusal("bridge: {axes: 2}\ncomedi: {y: {ai: {range: 300}}}"), "comedi.y.ai.range"));
}

TEST(ComediAxesConfig, TwoAxesOnOneChannelAreRefusedByTheLaterAxissKey) {
  // x's are the defaults: ao channel 0, ai channel 0, subdevice -1 (the card's first).
  std::string r = refusal(kCard + "comedi: {y: {ao: {channel: 0}, ai: {channel: 1}}}");
  EXPECT_TRUE(contains(r, "bridge.yaml: comedi.y.ao.channel: axis x drives ao subdevice auto channel 0 already")) << r;
  r = refusal(kCard + "comedi: {y: {ao: {channel: 1}, ai: {channel: 0}}}");
  EXPECT_TRUE(contains(r, "bridge.yaml: comedi.y.ai.channel: axis x reads ai subdevice auto channel 0 already")) << r;
  r = refusal(
      "bridge: {backend: comedi, axes: 3}\nrt: {required: false}\ncomedi: {y: {ao: {channel: 1}, ai: {channel: 1}}, "
      "z: {ao: {channel: 1}, ai: {channel: 2}}}");
  EXPECT_TRUE(contains(r, "comedi.z.ao.channel: axis y drives")) << r;
  r = refusal(
      "bridge: {backend: comedi, axes: 3}\nrt: {required: false}\ncomedi: {y: {ao: {channel: 1}, ai: {channel: 1}}, "
      "z: {ao: {channel: 2}, ai: {channel: 1}}}");
  EXPECT_TRUE(contains(r, "comedi.z.ai.channel: axis y reads")) << r;
  // The same channel number on another subdevice is another channel.
  EXPECT_EQ(refusal(kCard + "comedi: {ao: {subdevice: 1}, y: {ao: {subdevice: 3, channel: 0}, ai: {channel: 1}}}"),
            "accepted");
  // A simulator's config names the clash too, where both channels are given.
  EXPECT_TRUE(contains(refusal("bridge: {axes: 2}\ncomedi: {y: {ao: {channel: 0}}}"), "comedi.y.ao.channel"));
  EXPECT_EQ(refusal("bridge: {axes: 2}\ncomedi: {y: {ao: {channel: 1}}}"), "accepted");
}

TEST(ComediAxesConfig, KeysOfAnAxisTheStageLacksAreRefused) {
  std::string r = refusal(kCard + "comedi: {y: {ao: {channel: 1}, ai: {channel: 1}}, z: {ao: {channel: 2}}}");
  EXPECT_TRUE(contains(r, "bridge.yaml: comedi.z: the stage has 2 axes")) << r;
  r = refusal("bridge: {backend: comedi}\nrt: {required: false}\ncomedi: {y: {sensor: {offset_m: 0.0}}}");
  EXPECT_TRUE(contains(r, "bridge.yaml: comedi.y: the stage has 1 axis")) << r;
  r = refusal("bridge: {backend: sim}\ncomedi: {y: {ao: {channel: 1}}}");  // whatever the backend, as actuator.y
  EXPECT_TRUE(contains(r, "comedi.y: the stage has 1 axis")) << r;
  EXPECT_TRUE(contains(refusal(kCard + "comedi: {y: {ao: {chanel: 1}}}"), "comedi.y.ao.chanel: unknown key"));
}

TEST(ComediAxesConfig, EveryAxissKeysAreListed) {
  const std::vector<std::string>& keys = comedi_config_keys();
  for (const char* key : {"comedi.ao.channel", "comedi.sensor.offset_m", "comedi.y.ao.subdevice", "comedi.y.ai.aref",
                          "comedi.y.amplifier_gain_V_per_V", "comedi.z.sensor.scale_m_per_V", "comedi.z.ai.channel"}) {
    EXPECT_NE(std::find(keys.begin(), keys.end(), key), keys.end()) << key;
  }
  EXPECT_EQ(std::find(keys.begin(), keys.end(), "comedi.y.device"), keys.end()) << "the card's keys are shared";
  EXPECT_EQ(keys.size(), 3u + 5u + 3u * 11u);  // the card's, the enable's, each axis's
}

// deploy/config/bridge-comedi.yaml documents axis y with a commented example: uncommented, on a
// stage of two axes, it loads and the card takes it.
TEST(ComediAxesConfig, TheDeployedExampleOfAxisYWorksOnceUncommented) {
  std::ifstream in(std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/bridge-comedi.yaml");
  std::string text, line;
  bool block = false;
  int uncommented = 0;
  while (std::getline(in, line)) {
    block = line.starts_with("  # y:") || (block && line.starts_with("  # "));
    if (block) {
      line = "  " + line.substr(4);
      ++uncommented;
    }
    if (line.starts_with("  axes: 1")) line = "  axes: 2";
    text += line + "\n";
  }
  EXPECT_EQ(uncommented, 7);
  const BridgeSettings s = load_bridge_settings(Config::from_string(text, "bridge-comedi.yaml"));
  EXPECT_EQ(s.axes, 2);
  const ComediAxisSettings& y = s.comedi.axis(1);
  EXPECT_EQ(y.ao.channel, 1);
  EXPECT_EQ(y.ai.channel, 1);
  EXPECT_EQ(y.ai.aref, s.comedi.ai.aref);
  EXPECT_EQ(y.amplifier_gain_V_per_V, 30.0);
  EXPECT_EQ(y.sensor_scale_m_per_V, 2e-7);
  fake_comedi::reset();
  EXPECT_EQ(make_stage_backend(s)->axes(), 2);
}

// ---- the backend ----

// x: ao 0, ai 3 in [-5, 5] V differential; y: ao 1, ai 5 in [-10, 10] V, its own gain and a
// backwards sensor; z: ao 2, ai 7 in [-1, 1] V, its own gain and scale. Each input mirrors its
// own axis's output through a factor of its own, so that a crossed channel shows.
ComediSettings three_axes() {
  ComediSettings c;
  c.axes = 3;
  c.ao = {1, 0, 0, AREF_GROUND};
  c.ai = {0, 3, 1, AREF_DIFF};
  c.amplifier_gain_V_per_V = 25.0;
  c.sensor_scale_m_per_V = 2e-7;
  c.sensor_offset_m = 1e-6;
  c.axis(1) = ComediAxisSettings{{1, 1, 0, AREF_GROUND}, {0, 5, 0, AREF_GROUND}, 20.0, -1e-7, 2e-6};
  c.axis(2) = ComediAxisSettings{{1, 2, 0, AREF_GROUND}, {0, 7, 2, AREF_GROUND}, 50.0, 5e-8, 0.0};
  c.fault_limit = 3;
  return c;
}

// x [-250, 250] V safe 0 V; y [-100, 150] V safe 20 V; z [-30, 200] V safe 10 V.
std::array<ActuatorLimits, 3> three_limits() {
  std::array<ActuatorLimits, 3> a{};
  a[1].u_min_V = -100.0;
  a[1].u_max_V = 150.0;
  a[1].safe_u_V = 20.0;
  a[2].u_min_V = -30.0;
  a[2].u_max_V = 200.0;
  a[2].safe_u_V = 10.0;
  return a;
}

// Each axis's card volts -> DAC code ([-10, 10] V), and its safe code.
lsampl_t dac(double card_V) { return code(card_V, -10, 10); }
const std::array<lsampl_t, 3> kSafeCodes = {dac(0.0), dac(20.0 / 20.0), dac(10.0 / 50.0)};

class ComediAxesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    fake_comedi::reset();
    fake().mirror_ao[3] = 0;
    fake().mirror_ao[5] = 1;
    fake().mirror_ao[7] = 2;
    fake().mirror_scale[3] = 0.5;
    fake().mirror_scale[5] = 1.0;
    fake().mirror_scale[7] = 0.2;
  }
  fake_comedi::State& fake() { return fake_comedi::state(); }
  std::unique_ptr<ComediBackend> open(const ComediSettings& c = three_axes()) {
    const std::array<ActuatorLimits, 3> limits = three_limits();
    return std::make_unique<ComediBackend>(c, std::span<const ActuatorLimits>(limits).first(c.axes));
  }
  // Expects `l` to write each axis's `codes` on its channel (ao subdevice 1, channels 0, 1, 2).
  static void expect_writes(const fake_comedi::InsnList& l, std::size_t first, const std::array<lsampl_t, 3>& codes,
                            std::size_t axes = 3) {
    for (std::size_t i = 0; i < axes; ++i) {
      const fake_comedi::Insn& w = l.insns[first + i];
      EXPECT_EQ(w.insn, static_cast<unsigned>(INSN_WRITE)) << i;
      EXPECT_EQ(w.subdev, 1u) << i;
      EXPECT_EQ(w.chanspec, CR_PACK(i, 0, AREF_GROUND)) << i;
      EXPECT_EQ(w.data, codes[i]) << "axis " << i;
    }
  }
};

TEST_F(ComediAxesTest, OneListPerTickEveryAxissWriteThenEveryAxissRead) {
  auto b = open();
  EXPECT_EQ(b->axes(), 3);
  ASSERT_EQ(fake().lists.size(), 1u);  // the start: every axis's safe code, in one list
  ASSERT_EQ(fake().lists[0].n_insns, 3u);
  expect_writes(fake().lists[0], 0, kSafeCodes);

  const std::array<double, 3> u = {100.0, -50.0, 150.0};  // 4 V, -2.5 V, 3 V at the card
  std::array<StageReading, 3> out{};
  b->step_axes(u, 0.0, 1e-4, out);
  ASSERT_EQ(fake().lists.size(), 2u);
  const fake_comedi::InsnList& l = fake().lists.back();
  ASSERT_EQ(l.n_insns, 6u);
  expect_writes(l, 0, {dac(4.0), dac(-2.5), dac(3.0)});
  const std::array<unsigned, 3> reads = {CR_PACK(3, 1, AREF_DIFF), CR_PACK(5, 0, AREF_GROUND),
                                         CR_PACK(7, 2, AREF_GROUND)};
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(l.insns[3 + i].insn, static_cast<unsigned>(INSN_READ)) << i;
    EXPECT_EQ(l.insns[3 + i].subdev, 0u) << i;
    EXPECT_EQ(l.insns[3 + i].chanspec, reads[i]) << i;
    EXPECT_EQ(l.insns[3 + i].n, 1u) << i;
    EXPECT_EQ(out[i].flags, 0) << i;
    EXPECT_FALSE(out[i].go_safe) << i;
    EXPECT_TRUE(std::isnan(out[i].y_true_m)) << "hardware does not know the true position";
  }
  // Each axis's own input, range, scale and offset: the card's volts as the DAC wrote them, seen
  // through the input's factor, as the ADC codes them.
  const auto seen_m = [](double card_V, double factor, double lo, double hi, double scale, double offset) {
    return offset + scale * volts(code(factor * volts(dac(card_V), -10, 10), lo, hi), lo, hi);
  };
  EXPECT_DOUBLE_EQ(out[0].y_m, seen_m(4.0, 0.5, -5, 5, 2e-7, 1e-6));
  EXPECT_DOUBLE_EQ(out[1].y_m, seen_m(-2.5, 1.0, -10, 10, -1e-7, 2e-6));
  EXPECT_DOUBLE_EQ(out[2].y_m, seen_m(3.0, 0.2, -1, 1, 5e-8, 0.0));
  EXPECT_NEAR(out[1].y_m, 2e-6 + 2.5e-7, 1e-7 * 20.0 / kMaxdata);  // a backwards sensor: y rises as u falls
  EXPECT_EQ(b->counters().transfers.load(), 1u);
  // The conversions alone, axis by axis.
  EXPECT_EQ(b->dac_code(1, 100.0), dac(5.0));
  EXPECT_EQ(b->dac_code(2, 100.0), dac(2.0));
  EXPECT_DOUBLE_EQ(b->position_m(1, 40000), 2e-6 - 1e-7 * volts(40000, -10, 10));
  EXPECT_DOUBLE_EQ(b->position_m(2, 40000), 5e-8 * volts(40000, -1, 1));
  EXPECT_EQ(b->dac(2).max_V(), 10.0);
  EXPECT_EQ(b->adc(2).max_V(), 1.0);
}

TEST_F(ComediAxesTest, EachAxisClampsToItsOwnActuatorsRange) {
  auto b = open();
  std::array<StageReading, 3> out{};
  b->step_axes(std::array{1000.0, 1000.0, 1000.0}, 0.0, 1e-4, out);
  expect_writes(fake().lists.back(), 0, {dac(10.0), dac(150.0 / 20.0), dac(200.0 / 50.0)});
  b->step_axes(std::array{-1000.0, -1000.0, -1000.0}, 0.0, 1e-4, out);
  expect_writes(fake().lists.back(), 0, {dac(-10.0), dac(-100.0 / 20.0), dac(-30.0 / 50.0)});
  b->step_axes(std::array{0.0, std::nan(""), 0.0}, 0.0, 1e-4, out);  // never sent: y's low end
  expect_writes(fake().lists.back(), 0, {dac(0.0), dac(-5.0), dac(0.0)});
  EXPECT_EQ(b->counters().dac_clamped.load(), 0u);  // each DAC covers its actuator: checked at open
}

TEST_F(ComediAxesTest, ASaturatedOrFailedReadFlagsTheAxesConcernedOnly) {
  auto b = open();
  std::array<StageReading, 3> good{};
  b->step_axes(std::array{100.0, 50.0, 20.0}, 0.0, 1e-4, good);
  // Served to the reads in order: x, y, z of a tick, then the next tick's.
  fake().reads = {{2, 40000}, {2, kMaxdata}, {2, 30000},  // y saturated
                  {2, 40000}, {1, 0},                     // y's read fails: the list stops, z is not read
                  {-1, 0}};                               // the call fails: every axis
  std::array<StageReading, 3> out{};
  b->step_axes(std::array{100.0, 50.0, 20.0}, 0.0, 1e-4, out);
  EXPECT_EQ(out[0].flags, 0);
  EXPECT_DOUBLE_EQ(out[0].y_m, 1e-6 + 2e-7 * volts(40000, -5, 5));
  EXPECT_EQ(out[1].flags, sample_flags::kSensorFault);
  EXPECT_EQ(out[1].y_m, good[1].y_m);  // y's last good position
  EXPECT_EQ(out[2].flags, 0);
  EXPECT_DOUBLE_EQ(out[2].y_m, 5e-8 * volts(30000, -1, 1));
  const ComediCounters& c = b->counters();
  EXPECT_EQ(c.saturated.load(), 1u);
  EXPECT_EQ(c.axis_sensor_faults[0].load(), 0u);
  EXPECT_EQ(c.axis_sensor_faults[1].load(), 1u);
  EXPECT_EQ(c.axis_sensor_faults[2].load(), 0u);

  b->step_axes(std::array{100.0, 50.0, 20.0}, 0.0, 1e-4, out);
  EXPECT_EQ(out[0].flags, 0);
  EXPECT_EQ(out[1].flags, sample_flags::kSensorFault);
  EXPECT_EQ(out[2].flags, sample_flags::kSensorFault);
  EXPECT_EQ(out[2].y_m, 5e-8 * volts(30000, -1, 1));  // z's last good
  EXPECT_EQ(c.read_errors.load(), 2u);
  EXPECT_EQ(c.write_errors.load(), 0u);

  b->step_axes(std::array{100.0, 50.0, 20.0}, 0.0, 1e-4, out);
  for (const StageReading& r : out) EXPECT_EQ(r.flags, sample_flags::kSensorFault);
  EXPECT_EQ(c.read_errors.load(), 5u);
  EXPECT_EQ(c.write_errors.load(), 3u);
  EXPECT_EQ(c.sensor_faults.load(), 6u);  // the total over the axes
  EXPECT_EQ(c.axis_sensor_faults[0].load(), 1u);
  EXPECT_EQ(c.axis_sensor_faults[1].load(), 3u);
  EXPECT_EQ(c.axis_sensor_faults[2].load(), 2u);
  EXPECT_FALSE(out[0].go_safe);
  EXPECT_TRUE(out[1].go_safe) << "fault_limit 3: y's third in a row";
  EXPECT_FALSE(out[2].go_safe) << "z's second in a row";
  EXPECT_EQ(c.axis_fault_safe[1].load(), 1u);
}

TEST_F(ComediAxesTest, FaultLimitFaultsInARowOnAnyOneAxisAskForTheSafeState) {
  auto b = open();  // fault_limit 3
  std::array<StageReading, 3> out{};
  // Faults on x, then y, then x again: no axis has three in a row.
  fake().reads = {{2, 0}, {2, 30000}, {2, 30000}, {2, 30000}, {2, 0}, {2, 30000}, {2, 0}, {2, 30000}, {2, 30000}};
  for (int k = 0; k < 3; ++k) {
    b->step_axes(std::array{0.0, 20.0, 10.0}, 0.0, 1e-4, out);
    for (const StageReading& r : out) EXPECT_FALSE(r.go_safe) << k;
  }
  // z saturates three ticks in a row while x and y read well.
  fake().reads.clear();
  fake().next_read = 0;
  for (int k = 0; k < 4; ++k) fake().reads.insert(fake().reads.end(), {{2, 30000}, {2, 30000}, {2, kMaxdata}});
  for (int k = 0; k < 4; ++k) {
    b->step_axes(std::array{0.0, 20.0, 10.0}, 0.0, 1e-4, out);
    EXPECT_FALSE(out[0].go_safe);
    EXPECT_FALSE(out[1].go_safe);
    EXPECT_EQ(out[2].go_safe, k >= 2) << k;
  }
  const ComediCounters& c = b->counters();
  EXPECT_EQ(c.fault_safe.load(), 1u);
  EXPECT_EQ(c.axis_fault_safe[2].load(), 1u);
  std::vector<std::pair<std::string, std::uint64_t>> entries;
  b->append_counters(entries);
  const auto value = [&](const std::string& name) -> long {
    for (const auto& [n, v] : entries) {
      if (n == name) return static_cast<long>(v);
    }
    return -1;
  };
  EXPECT_EQ(value("sensor_faults"), 7);  // the total: x 2, y 1, z 4
  EXPECT_EQ(value("x_sensor_faults"), 2);
  EXPECT_EQ(value("y_sensor_faults"), 1);
  EXPECT_EQ(value("z_sensor_faults"), 4);
  EXPECT_EQ(value("sensor_fault_safe"), 1);
  EXPECT_EQ(value("z_sensor_fault_safe"), 1);
  EXPECT_EQ(value("x_sensor_fault_safe"), 0);
  EXPECT_EQ(entries.size(), 11u + 2u * 3u);
}

TEST_F(ComediAxesTest, HoldSafeTheDestructorAndAnEmergencyWriteEachAxissOwnSafeCode) {
  {
    auto b = open();
    std::array<StageReading, 3> out{};
    b->step_axes(std::array{200.0, 120.0, 180.0}, 0.0, 1e-4, out);
    b->hold_safe(std::array{0.0, 20.0, 10.0});
    ASSERT_EQ(fake().lists.back().n_insns, 3u);
    expect_writes(fake().lists.back(), 0, kSafeCodes);
    // The safe voltages the bridge passes are the ones written.
    b->hold_safe(std::array{-10.0, 0.0, 5.0});
    expect_writes(fake().lists.back(), 0, {dac(-10.0 / 25.0), dac(0.0), dac(5.0 / 50.0)});
    // step() drives x only; the others hold what they were last given.
    b->step(100.0, 0.0, 1e-4);
    ASSERT_EQ(fake().lists.back().n_insns, 6u);
    expect_writes(fake().lists.back(), 0, {dac(4.0), dac(0.0), dac(5.0 / 50.0)});
    b->step_axes(std::array{200.0, 120.0, 180.0}, 0.0, 1e-4, out);
    b->step(50.0, 0.0, 1e-4);  // y and z hold the bridge's last tick
    expect_writes(fake().lists.back(), 0, {dac(2.0), dac(120.0 / 20.0), dac(180.0 / 50.0)});
    const long lists = static_cast<long>(fake().lists.size());
    EXPECT_TRUE(b->emergency_safe());  // the fatal-signal path: ramped to the last safe codes, then one list
    ASSERT_GT(static_cast<long>(fake().lists.size()), lists + 1);
    expect_writes(fake().lists.back(), 0, {dac(-10.0 / 25.0), dac(0.0), dac(5.0 / 50.0)});
    expect_writes(fake().lists[fake().lists.size() - 2], 0, {dac(-10.0 / 25.0), dac(0.0), dac(5.0 / 50.0)});
    b->step_axes(std::array{200.0, 120.0, 180.0}, 0.0, 1e-4, out);
  }
  // The destructor's: each actuator's own safe voltage, ramped there, then one list.
  expect_writes(fake().lists.back(), 0, kSafeCodes);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(fake().ao_counts[i], kSafeCodes[i]) << i;
  EXPECT_EQ(fake().ao_writes[3], 0);
  EXPECT_EQ(fake().closes, fake().opens);
}

TEST_F(ComediAxesTest, ATickOfThreeAxesDoesNotAllocate) {
  auto b = open();
  std::array<StageReading, 3> out{};
  std::array<double, 3> u{};
  b->step_axes(u, 0, 1e-4, out);
  fake().reads.push_back({2, kMaxdata});  // a fault's path too
  fake().reads.push_back({1, 0});
  const testing::AllocationCounter count;
  for (int k = 0; k < 1000; ++k) {
    u = {k * 0.1, -k * 0.05, k * 0.02};
    b->step_axes(u, k * 1e-4, 1e-4, out);
  }
  b->step(1.0, 0, 1e-4);
  b->hold_safe(std::array{0.0, 20.0, 10.0});
  EXPECT_EQ(count.allocations(), 0u);
  EXPECT_EQ(b->counters().sensor_faults.load(), 3u);  // the scripted faults did run
}

TEST_F(ComediAxesTest, ARefusalAfterOpeningLeavesEveryUsableOutputSafe) {
  const auto refused = [&](const ComediSettings& c) -> std::string {
    SetUp();
    try {
      open(c);
    } catch (const ConfigError& e) {
      EXPECT_EQ(fake().closes, fake().opens) << "the device stays open";
      return e.what();
    }
    return "accepted";
  };
  // Every axis's output usable: all three written their safe codes, then refused.
  ComediSettings c = three_axes();
  c.axis(2).amplifier_gain_V_per_V = 10.0;  // z's 200 V needs 20 V: the DAC has 10 V
  std::string r = refused(c);
  EXPECT_TRUE(contains(r, "comedi.z.ao.range: the DAC's [-10, 10] V does not cover actuator.z.u_min_V")) << r;
  EXPECT_TRUE(contains(r, "[-3, 20] V")) << r;
  ASSERT_EQ(fake().lists.size(), 1u);
  expect_writes(fake().lists[0], 0, {kSafeCodes[0], kSafeCodes[1], dac(1.0)});  // z's 10 V / 10
  c = three_axes();
  c.axis(1).ai.channel = 16;
  r = refused(c);
  EXPECT_TRUE(contains(r, "comedi.y.ai.channel: subdevice 0 has 16 channels")) << r;
  ASSERT_EQ(fake().lists.size(), 1u);
  expect_writes(fake().lists[0], 0, kSafeCodes);
  c = three_axes();
  c.axis(2).ai.range = 3;
  EXPECT_TRUE(contains(refused(c), "comedi.z.ai.range"));
  EXPECT_EQ(fake().writes, 3);
  // y's output does not exist: x's and z's are still taken to their safe voltages.
  c = three_axes();
  c.axis(1).ao.channel = static_cast<int>(fake_comedi::kAoChannels);
  r = refused(c);
  EXPECT_TRUE(contains(r, "comedi.y.ao.channel: subdevice 1 has 4 channels")) << r;
  ASSERT_EQ(fake().lists.size(), 1u);
  ASSERT_EQ(fake().lists[0].n_insns, 2u);
  EXPECT_EQ(fake().ao_writes[0], 1);
  EXPECT_EQ(fake().ao_writes[2], 1);
  EXPECT_EQ(fake().ao_counts[2], kSafeCodes[2]);
  c = three_axes();
  c.axis(1).ao.subdevice = 2;  // the digital I/O
  EXPECT_TRUE(contains(refused(c), "comedi.y.ao.subdevice: subdevice 2 is not an analog output"));
  EXPECT_EQ(fake().ao_writes[1], 0);
  EXPECT_EQ(fake().writes, 2);
  // Two axes on one output once the card's first subdevice is known: the later one is refused
  // and never written.
  c = three_axes();
  c.ao.subdevice = -1;
  c.axis(2).ao = {1, 0, 0, AREF_GROUND};
  r = refused(c);
  EXPECT_TRUE(contains(r, "comedi.z.ao.channel: axis x drives ao subdevice 1 channel 0 already")) << r;
  EXPECT_EQ(fake().ao_writes[0], 1);
  EXPECT_EQ(fake().ao_counts[0], kSafeCodes[0]);
  EXPECT_EQ(fake().ao_writes[1], 1);
  c = three_axes();
  c.axis(1).ai = {-1, 3, 0, AREF_GROUND};  // x reads subdevice 0 channel 3
  r = refused(c);
  EXPECT_TRUE(contains(r, "comedi.y.ai.channel: axis x reads ai subdevice 0 channel 3 already")) << r;
  EXPECT_EQ(fake().writes, 3);
  c = three_axes();
  EXPECT_EQ(refused(c), "accepted");
}

TEST_F(ComediAxesTest, AnActuatorPerAxisOrNothingIsOpened) {
  const std::array<ActuatorLimits, 3> limits = three_limits();
  EXPECT_EQ(testing::refused_field([&] { ComediBackend(three_axes(), std::span(limits).first(2)); }), "bridge.axes");
  EXPECT_EQ(testing::refused_field([&] { ComediBackend(three_axes(), limits[0]); }), "bridge.axes");
  EXPECT_EQ(fake().opens, 0);
}

TEST_F(ComediAxesTest, TheBridgesSettingsMakeABackendOfEveryAxisWithItsOwnActuator) {
  const BridgeSettings s =
      load(kCard +
           "comedi: {ao: {subdevice: 1}, ai: {range: 1}, y: {ao: {channel: 1}, ai: {channel: 5}}}\n"
           "actuator: {y: {u_min_V: -40.0, u_max_V: 80.0, safe_u_V: 25.0}}");
  fake_comedi::reset();
  const std::unique_ptr<StageBackend> b = make_stage_backend(s);
  EXPECT_EQ(b->axes(), 2);
  expect_writes(fake().lists.back(), 0, {dac(0.0), dac(1.0)}, 2);  // y's own safe 25 V / 25
  std::array<StageReading, 2> out{};
  b->step_axes(std::array{500.0, 500.0}, 0.0, 1e-4, out);
  ASSERT_EQ(fake().lists.back().n_insns, 4u);
  expect_writes(fake().lists.back(), 0, {dac(10.0), dac(80.0 / 25.0)}, 2);
  EXPECT_EQ(fake().lists.back().insns[3].chanspec, CR_PACK(5, 1, AREF_GROUND));  // y's input, x's range
}

// ---- the probe, on one axis ----

std::string probe(const BridgeSettings& s, const ProbeOptions& o, int& rc) {
  char* text = nullptr;
  std::size_t size = 0;
  std::FILE* out = ::open_memstream(&text, &size);
  rc = probe_hardware(s, o, out);
  std::fclose(out);
  std::string result(text, size);
  std::free(text);
  return result;
}

TEST_F(ComediAxesTest, TheProbeDrivesOneAxisWhileTheOthersHoldTheirSafeVoltage) {
  const BridgeSettings s = load(kCard +
                                "comedi: {ao: {subdevice: 1}, y: {ao: {channel: 1}, ai: {channel: 5}}}\n"
                                "actuator: {y: {safe_u_V: 50.0}}");
  fake().mirror_scale[5] = 0.5;
  ProbeOptions o;
  o.drive = true;
  o.axis = 1;
  o.duration_s = 0.05;
  int rc = -1;
  std::string out = probe(s, o, rc);
  EXPECT_EQ(rc, 0) << out;
  for (const char* says : {"comedi y: ao subdevice 1 channel 1", "driving axis y: triangle 2 V -> 3 V -> 1 V -> 2 V",
                           "measured: sensor +0.5", "with comedi.y.sensor.scale_m_per_V", "verdict: sign OK"}) {
    EXPECT_TRUE(contains(out, says)) << says << " not in:\n" << out;
  }
  std::size_t ticks = 0;
  for (const fake_comedi::InsnList& l : fake().lists) {
    if (l.n_insns != 4) continue;
    ++ticks;
    ASSERT_EQ(l.insns[0].data, dac(0.0)) << "x moved during y's probe";
  }
  EXPECT_GE(ticks, 50u);
  EXPECT_EQ(fake().ao_counts[0], dac(0.0));
  EXPECT_EQ(fake().ao_counts[1], dac(2.0));  // y back at its safe 50 V
  // A backwards sensor names the axis's own key.
  SetUp();
  fake().mirror_scale[5] = -0.5;
  out = probe(s, o, rc);
  EXPECT_EQ(rc, 1) << out;
  EXPECT_TRUE(contains(out, "SIGN REVERSED")) << out;
  EXPECT_TRUE(contains(out, "negate comedi.y.sensor.scale_m_per_V")) << out;
  // Without --yes it says what it would drive; an axis the stage lacks is refused.
  o.drive = false;
  out = probe(s, o, rc);
  EXPECT_EQ(rc, 0) << out;
  EXPECT_TRUE(contains(out, "to axis y's ao subdevice 1 channel 1")) << out;
  o.axis = 2;
  out = probe(s, o, rc);
  EXPECT_EQ(rc, 2) << out;
  EXPECT_TRUE(contains(out, "the stage has 2 axes")) << out;
}

// ---- under the bridge's real-time thread ----

BridgeSettings two_axis_bridge() {
  BridgeSettings s;
  s.backend = "comedi";
  s.axes = 2;
  s.rt.ticks_per_wake = 1;
  s.block_ticks = 20;
  s.auto_arm = true;
  s.limits.safe_u_V = 0.0;
  s.limits.safe_ramp_V_per_s = 1e4;  // 1 V per tick at the piezo
  s.limits.watchdog_s = 1.0;
  ActuatorLimits y = s.limits;
  y.u_min_V = -100.0;
  y.u_max_V = 100.0;
  y.safe_u_V = 25.0;
  s.axis_limits[1] = y;
  s.stop_ramp_timeout_s = 2.0;
  s.max_stall_s = 1.0;  // not the stall guard's test (a busy machine may miss 10 ms in a second)
  s.comedi.axes = 2;
  s.comedi.ao = {1, 0, 0, AREF_GROUND};
  s.comedi.ai = {0, 0, 0, AREF_GROUND};
  s.comedi.axis(1).ao = {1, 1, 0, AREF_GROUND};
  s.comedi.axis(1).ai = {0, 1, 0, AREF_GROUND};
  s.comedi.fault_limit = 10;
  return s;
}

// Started, armed by the first commands and driven to (x_V, y_V).
std::unique_ptr<BridgeRealtime> drive_to(const BridgeSettings& s, double x_V, double y_V) {
  auto rt = std::make_unique<BridgeRealtime>(s, make_stage_backend(s));
  for (std::int64_t k = 0; k < 8000; ++k) {
    const std::array<CommandTick, 2> tick{CommandTick{k, x_V, std::nan(""), 1, 2},
                                          CommandTick{k, y_V, std::nan(""), 1, 2}};
    EXPECT_TRUE(rt->push_commands(tick));
  }
  rt->start();
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  bool there = false;
  while (!there && std::chrono::steady_clock::now() < until) {
    while (const auto t = rt->pop_tick()) there = there || (t->ticks[0].u_V == x_V && t->ticks[1].u_V == y_V);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_TRUE(there) << "the stage never got to " << x_V << " V, " << y_V << " V";
  return rt;
}

TEST_F(ComediAxesTest, TheBridgesStopRampsEveryAxisToItsOwnSafeVoltage) {
  const BridgeSettings s = two_axis_bridge();
  auto rt = drive_to(s, 150.0, -60.0);
  rt->begin_safe_stop();
  const SafeStopResult r = rt->stop();
  EXPECT_TRUE(r.reached);
  const auto& lists = fake().lists;
  ASSERT_GE(lists.size(), 3u);
  expect_writes(lists.front(), 0, {dac(0.0), dac(1.0)}, 2);  // safe before anything was armed
  // Every tick a list of both writes, then both reads; y within its own range and ramp.
  const double count_V = 20.0 / kMaxdata;
  double y_prev_V = 1.0;
  for (std::size_t i = 1; i < lists.size(); ++i) {
    const fake_comedi::InsnList& l = lists[i];
    if (l.n_insns == 2) continue;  // hold_safe's
    ASSERT_EQ(l.n_insns, 4u) << i;
    EXPECT_EQ(l.insns[2].insn, static_cast<unsigned>(INSN_READ));
    const double y_V = volts(l.insns[1].data, -10, 10);
    ASSERT_GE(y_V * 25.0, -100.0 - 25.0 * count_V) << i;
    ASSERT_LE(std::abs(y_V - y_prev_V) * 25.0, s.limits.slew_V_per_s * 1e-4 + 25.0 * count_V) << i;
    y_prev_V = y_V;
  }
  expect_writes(lists.back(), 0, {dac(0.0), dac(1.0)}, 2);  // hold_safe's, last
  EXPECT_EQ(lists.back().n_insns, 2u);
  rt.reset();
  EXPECT_EQ(fake().ao_counts[0], dac(0.0));
  EXPECT_EQ(fake().ao_counts[1], dac(1.0));  // y's 25 V / 25
  EXPECT_EQ(fake().closes, 1);
}

TEST_F(ComediAxesTest, OneAxissFailingSensorTakesEveryAxisToSafe) {
  const BridgeSettings s = two_axis_bridge();
  fake().mirror_ao[1] = 1;
  auto& reads = fake().reads;
  for (int i = 0; i < 600; ++i) reads.insert(reads.end(), {{2, 40000}, {2, 30000}});  // x's, y's read
  for (int i = 0; i < 30; ++i) reads.insert(reads.end(), {{2, 40000}, {1, 0}});       // y's cable comes off
  auto rt = drive_to(s, 80.0, 40.0);
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  int y_faults_before_safe = 0, x_faults = 0;
  bool safe = false;
  while (!safe && std::chrono::steady_clock::now() < until) {
    while (const auto t = rt->pop_tick()) {
      x_faults += (t->ticks[0].flags & sample_flags::kSensorFault) != 0 ? 1 : 0;
      if (safe) continue;
      if ((t->ticks[0].flags & sample_flags::kSafeState) != 0 && t->tick().seq > 100) {
        safe = true;
      } else if ((t->ticks[1].flags & sample_flags::kSensorFault) != 0) {
        ++y_faults_before_safe;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_TRUE(safe) << "armed with commands buffered, yet never safe";
  EXPECT_EQ(y_faults_before_safe, s.comedi.fault_limit);
  EXPECT_EQ(x_faults, 0);
  rt->stop();
  expect_writes(fake().lists.back(), 0, {dac(0.0), dac(1.0)}, 2);
  const auto& c = dynamic_cast<const ComediBackend&>(rt->backend()).counters();
  EXPECT_EQ(c.axis_sensor_faults[0].load(), 0u);
  EXPECT_EQ(c.axis_sensor_faults[1].load(), 30u);
  EXPECT_EQ(c.axis_fault_safe[1].load(), 1u);
}

}  // namespace
}  // namespace hystloop
