// bridge.backend: comedi against the fake card (tests/hw/fake_comedi.hpp): the config and its
// refusals, the safe write before anything else, one instruction list per tick (a write, then a
// read), the conversions both ways (range tables and softcal), the clamp before the DAC, the
// fault counting and the request to go safe, the refusal of a config the card cannot do after
// the device was opened (the safe voltage written first), no allocation per tick, the ramps to
// the safe voltage, and the amplifier enable line (level, active low, heartbeat).
#include <array>
#include "bridge/comedi_backend.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "bridge/bridge_settings.hpp"
#include "fake_comedi.hpp"
#include "support/allocation_counter.hpp"
#include "support/refusal.hpp"
#include "support/text.hpp"

namespace hystloop {
namespace {

using fake_comedi::kMaxdata;

using testing::contains;

ComediSettings settings() {
  ComediSettings c;
  c.ao = {1, 0, 0, AREF_GROUND};
  c.ai = {0, 3, 1, AREF_DIFF};  // channel 3, range 1 = [-5, 5] V, differential
  c.amplifier_gain_V_per_V = 25.0;
  c.sensor_scale_m_per_V = 2e-7;
  c.sensor_offset_m = 1e-6;
  c.fault_limit = 3;
  c.calibration = "auto";
  return c;
}

ActuatorLimits limits(double safe_u_V = 0.0) {
  ActuatorLimits a;  // [-250, 250] V
  a.safe_u_V = safe_u_V;
  return a;
}

// comedilib's range-table conversions (comedi_from_phys / comedi_to_phys).
lsampl_t code(double V, double lo, double hi) {
  return static_cast<lsampl_t>(std::floor((V - lo) / (hi - lo) * kMaxdata + 0.5));
}
double volts(lsampl_t counts, double lo, double hi) { return lo + (hi - lo) * counts / double(kMaxdata); }

class ComediBackendTest : public ::testing::Test {
 protected:
  void SetUp() override { fake_comedi::reset(); }
  fake_comedi::State& fake() { return fake_comedi::state(); }
};

std::string refusal(const std::string& yaml) {
  return testing::config_refusal([&] { load_bridge_settings(Config::from_string(yaml, "bridge.yaml")); });
}

TEST(ComediConfig, KeysAreValidatedAndRefusalsNameTheField) {
  const BridgeSettings d =
      load_bridge_settings(Config::load_file(std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/bridge-comedi.yaml"));
  EXPECT_EQ(d.backend, "comedi");
  EXPECT_EQ(d.comedi.device, "/dev/comedi0");
  EXPECT_EQ(d.comedi.ai.aref, AREF_DIFF);
  EXPECT_EQ(d.comedi.amplifier_gain_V_per_V, 25.0);
  EXPECT_EQ(d.rt.ticks_per_wake, 1);
  const std::string c = "bridge: {backend: comedi}\nrt: {ticks_per_wake: 1, required: false}\n";
  EXPECT_EQ(refusal(c), "accepted");
  EXPECT_TRUE(contains(refusal(c + "comedi: {ai: {aref: floating}}"), "bridge.yaml: comedi.ai.aref"))
      << refusal(c + "comedi: {ai: {aref: floating}}");
  EXPECT_TRUE(contains(refusal(c + "comedi: {ao: {channel: -1}}"), "bridge.yaml: comedi.ao.channel"));
  EXPECT_TRUE(contains(refusal(c + "comedi: {ai: {subdevice: -2}}"), "bridge.yaml: comedi.ai.subdevice"));
  EXPECT_TRUE(contains(refusal(c + "comedi: {amplifier_gain_V_per_V: 0}"), "comedi.amplifier_gain_V_per_V"));
  EXPECT_TRUE(contains(refusal(c + "comedi: {sensor: {scale_m_per_V: 0}}"), "comedi.sensor.scale_m_per_V"));
  EXPECT_TRUE(contains(refusal(c + "comedi: {fault_limit: 0}"), "comedi.fault_limit"));
  EXPECT_TRUE(contains(refusal(c + "comedi: {device: ''}"), "comedi.device"));
  EXPECT_TRUE(contains(refusal(c + "comedi: {sensor: {scale_m: 1}}"), "comedi.sensor.scale_m: unknown key"));
  // A card cannot run ticks back to back.
  EXPECT_TRUE(contains(refusal("bridge: {backend: comedi}\nrt: {ticks_per_wake: 20}"), "rt.ticks_per_wake"));
  EXPECT_TRUE(contains(refusal("bridge: {backend: daq}"), "must be sim, ro, series or comedi"));
  // The amplifier enable: a mode, a polarity, a heartbeat a tick can carry (two ticks a period).
  EXPECT_TRUE(contains(refusal(c + "comedi: {enable: {mode: pulse}}"), "bridge.yaml: comedi.enable.mode"));
  EXPECT_TRUE(contains(refusal(c + "comedi: {enable: {active: middle}}"), "bridge.yaml: comedi.enable.active"));
  EXPECT_TRUE(contains(refusal(c + "comedi: {enable: {channel: -2}}"), "bridge.yaml: comedi.enable.channel"));
  EXPECT_TRUE(contains(refusal(c + "comedi: {enable: {heartbeat_hz: 5001}}"), "comedi.enable.heartbeat_hz"));
  EXPECT_EQ(refusal(c + "comedi: {enable: {channel: 0, mode: heartbeat, heartbeat_hz: 5000, active: low}}"),
            "accepted");
  // The simulators ignore the comedi keys.
  EXPECT_EQ(refusal("bridge: {backend: sim}\ncomedi: {device: /dev/comedi1}"), "accepted");
}

TEST_F(ComediBackendTest, WritesTheSafeVoltageBeforeAnythingElse) {
  ComediBackend b(settings(), limits(50.0));  // 50 V at the piezo: 2 V at the card
  ASSERT_EQ(fake().lists.size(), 1u);
  const auto& first = fake().lists[0];
  ASSERT_EQ(first.n_insns, 1u);
  EXPECT_EQ(first.insns[0].insn, static_cast<unsigned>(INSN_WRITE));
  EXPECT_EQ(first.insns[0].subdev, 1u);
  EXPECT_EQ(first.insns[0].chanspec, CR_PACK(0, 0, AREF_GROUND));
  EXPECT_EQ(first.insns[0].data, code(2.0, -10, 10));
  EXPECT_EQ(b.counters().safe_writes.load(), 1u);
  EXPECT_FALSE(b.dac().softcal());
  EXPECT_TRUE(b.calibration_path().empty());
}

TEST_F(ComediBackendTest, OneInstructionListPerTickAWriteThenARead) {
  fake().mirror_gain = 0.5;
  ComediBackend b(settings(), limits());
  const std::size_t before = fake().lists.size();
  const StageReading r = b.step(100.0, 0.0, 1e-4);  // 4 V at the card; the sensor sees 2 V
  ASSERT_EQ(fake().lists.size(), before + 1);
  const auto& l = fake().lists.back();
  ASSERT_EQ(l.n_insns, 2u);
  EXPECT_EQ(l.insns[0].insn, static_cast<unsigned>(INSN_WRITE));
  EXPECT_EQ(l.insns[0].subdev, 1u);
  EXPECT_EQ(l.insns[0].chanspec, CR_PACK(0, 0, AREF_GROUND));
  EXPECT_EQ(l.insns[0].n, 1u);
  EXPECT_EQ(l.insns[0].data, code(4.0, -10, 10));
  EXPECT_EQ(l.insns[1].insn, static_cast<unsigned>(INSN_READ));
  EXPECT_EQ(l.insns[1].subdev, 0u);
  EXPECT_EQ(l.insns[1].chanspec, CR_PACK(3, 1, AREF_DIFF));
  EXPECT_EQ(l.insns[1].n, 1u);
  EXPECT_EQ(r.flags, 0);
  EXPECT_FALSE(r.go_safe);
  EXPECT_NEAR(r.y_m, 1e-6 + 2e-7 * 2.0, 2e-7 * 10.0 / kMaxdata);  // within a count of the ADC
  EXPECT_EQ(b.counters().transfers.load(), 1u);
}

TEST_F(ComediBackendTest, ConvertsBothWaysThroughTheRangeTables) {
  ComediBackend b(settings(), limits());
  for (const double u : {-250.0, -137.5, 0.0, 0.01, 99.9, 250.0}) {
    EXPECT_EQ(b.dac_code(u), code(u / 25.0, -10, 10)) << u;
  }
  for (const lsampl_t counts : {1u, 1000u, 32768u, 65534u}) {
    EXPECT_DOUBLE_EQ(b.position_m(counts), 1e-6 + 2e-7 * volts(counts, -5, 5)) << counts;
  }
  EXPECT_TRUE(std::isnan(b.position_m(0)));  // the ends of the range: saturated
  EXPECT_TRUE(std::isnan(b.position_m(kMaxdata)));
}

TEST_F(ComediBackendTest, UsesTheBoardsSoftcalPolynomialsWhenItHasACalibrationFile) {
  fake().calibration = true;
  ComediBackend b(settings(), limits());
  EXPECT_TRUE(b.dac().softcal());
  EXPECT_TRUE(b.adc().softcal());
  EXPECT_EQ(b.calibration_path(), "/var/lib/comedi/calibrations/fake_board_comedi0");
  const double g = fake_comedi::softcal_gain(), o = fake_comedi::softcal_offset_V();
  // V -> counts: the inverse of counts -> V = o + g * (counts - maxdata/2) * span/maxdata.
  const double card_V = 4.0;
  const double expected = kMaxdata / 2.0 + (card_V - o) / (g * 20.0 / kMaxdata);
  EXPECT_EQ(b.dac_code(100.0), static_cast<lsampl_t>(std::nearbyint(expected)));
  EXPECT_DOUBLE_EQ(b.position_m(40000), 1e-6 + 2e-7 * (o + g * (40000 - kMaxdata / 2.0) * 10.0 / kMaxdata));
  ComediSettings none = settings();
  none.calibration = "none";
  fake_comedi::reset();
  fake().calibration = true;
  ComediBackend tables(none, limits());
  EXPECT_FALSE(tables.dac().softcal());
}

TEST_F(ComediBackendTest, ClampsToTheActuatorsRangeBeforeTheDac) {
  ComediBackend b(settings(), limits());
  b.step(400.0, 0.0, 1e-4);  // above u_max_V = 250 V: 10 V at the card, not 16 V
  EXPECT_EQ(fake().lists.back().insns[0].data, code(10.0, -10, 10));
  b.step(-1e9, 0.0, 1e-4);
  EXPECT_EQ(fake().lists.back().insns[0].data, code(-10.0, -10, 10));
  b.step(std::nan(""), 0.0, 1e-4);  // never sent by BridgeCore; the low end, not garbage
  EXPECT_EQ(fake().lists.back().insns[0].data, code(-10.0, -10, 10));
  ActuatorLimits narrow = limits();
  narrow.u_min_V = -50.0;
  narrow.u_max_V = 100.0;
  fake_comedi::reset();
  ComediBackend n(settings(), narrow);
  n.step(200.0, 0.0, 1e-4);
  EXPECT_EQ(fake().lists.back().insns[0].data, code(4.0, -10, 10));
  n.step(-200.0, 0.0, 1e-4);
  EXPECT_EQ(fake().lists.back().insns[0].data, code(-2.0, -10, 10));
  EXPECT_EQ(n.counters().dac_clamped.load(), 0u);  // the DAC's range covers the actuator's: checked at open
}

TEST_F(ComediBackendTest, FailedOrSaturatedReadsAreFaultsAndEnoughInARowAskForTheSafeState) {
  fake().mirror_gain = 0.5;
  ComediBackend b(settings(), limits());  // fault_limit 3
  const StageReading good = b.step(100.0, 0, 1e-4);
  ASSERT_EQ(good.flags, 0);
  fake().reads = {{1, 0}, {2, kMaxdata}, {-1, 0}, {2, 0}, {2, 40000}, {1, 0}};
  const StageReading f1 = b.step(100.0, 0, 1e-4);  // the read failed
  EXPECT_EQ(f1.flags, sample_flags::kSensorFault);
  EXPECT_EQ(f1.y_m, good.y_m);  // the last good value
  EXPECT_FALSE(f1.go_safe);
  const StageReading f2 = b.step(100.0, 0, 1e-4);  // saturated high
  EXPECT_EQ(f2.flags, sample_flags::kSensorFault);
  EXPECT_FALSE(f2.go_safe);
  const StageReading f3 = b.step(100.0, 0, 1e-4);  // the call failed: the third in a row
  EXPECT_TRUE(f3.go_safe);
  const StageReading f4 = b.step(100.0, 0, 1e-4);  // saturated low: still asking
  EXPECT_TRUE(f4.go_safe);
  const StageReading ok = b.step(100.0, 0, 1e-4);
  EXPECT_EQ(ok.flags, 0);
  EXPECT_FALSE(ok.go_safe);
  EXPECT_DOUBLE_EQ(ok.y_m, 1e-6 + 2e-7 * volts(40000, -5, 5));
  EXPECT_FALSE(b.step(100.0, 0, 1e-4).go_safe);  // one fault after a good read: counted, not enough
  const ComediCounters& c = b.counters();
  EXPECT_EQ(c.sensor_faults.load(), 5u);
  EXPECT_EQ(c.read_errors.load(), 3u);
  EXPECT_EQ(c.write_errors.load(), 1u);
  EXPECT_EQ(c.saturated.load(), 2u);
  EXPECT_EQ(c.fault_safe.load(), 1u);
  std::vector<std::pair<std::string, std::uint64_t>> entries;
  b.append_counters(entries);
  bool found = false;
  for (const auto& [name, value] : entries) found = found || (name == "sensor_faults" && value == 5);
  EXPECT_TRUE(found);
}

TEST_F(ComediBackendTest, ATickDoesNotAllocate) {
  ComediBackend b(settings(), limits());
  b.step(0.0, 0, 1e-4);
  const testing::AllocationCounter count;
  for (int k = 0; k < 1000; ++k) b.step(k * 0.1, k * 1e-4, 1e-4);
  b.hold_safe(std::array{0.0});
  EXPECT_EQ(count.allocations(), 0u);
}

// The output codes written since list `from` (every list writes the output first).
std::vector<lsampl_t> codes_since(std::size_t from) {
  std::vector<lsampl_t> codes;
  for (std::size_t i = from; i < fake_comedi::state().lists.size(); ++i) {
    codes.push_back(fake_comedi::state().lists[i].insns[0].data);
  }
  return codes;
}

// The codes step by at most the safe ramp's (one count of rounding) and end at `safe`.
void expect_ramp(const std::vector<lsampl_t>& codes, lsampl_t safe, double ramp_V_per_s) {
  ASSERT_FALSE(codes.empty());
  const double max_step = ramp_V_per_s * ComediBackend::kRampTick_s / 25.0 * kMaxdata / 20.0 + 1.0;
  for (std::size_t i = 1; i < codes.size(); ++i) {
    ASSERT_LE(std::abs(double(codes[i]) - double(codes[i - 1])), max_step) << i;
  }
  EXPECT_EQ(codes.back(), safe);
}

TEST_F(ComediBackendTest, HoldSafeAndTheDestructorRampToTheSafeVoltage) {
  const ActuatorLimits a = limits(-25.0);  // 1e3 V/s: 0.1 V a ramp tick at the piezo
  std::size_t from = 0;
  {
    ComediBackend b(settings(), a);
    b.step(200.0, 0, 1e-4);
    from = fake().lists.size();
    b.hold_safe(std::array{-25.0});
    std::vector<lsampl_t> codes = codes_since(from);
    // 225 V in steps of 0.1 V at most (whole DAC counts: 13 of 13.1), then the safe list.
    EXPECT_GE(codes.size(), 2251u);
    EXPECT_LE(codes.size(), 2271u);
    expect_ramp(codes, code(-1.0, -10, 10), a.safe_ramp_V_per_s);
    EXPECT_EQ(fake().lists.back().n_insns, 1u);
    EXPECT_EQ(b.counters().safe_ramps.load(), 1u);
    from = fake().lists.size();
    b.hold_safe(std::array{-25.0});  // there already: one list, no ramp
    EXPECT_EQ(fake().lists.size(), from + 1);
    EXPECT_EQ(b.counters().safe_ramps.load(), 1u);
    b.step(0.0, 0, 1e-4);
    from = fake().lists.size();
  }
  const std::vector<lsampl_t> codes = codes_since(from - 1);  // from the step to 0 V: the destructor's ramp
  EXPECT_EQ(codes.front(), code(0.0, -10, 10));
  EXPECT_GE(codes.size(), 252u);  // 25 V in 0.1 V steps at most
  expect_ramp(codes, code(-1.0, -10, 10), a.safe_ramp_V_per_s);
  EXPECT_EQ(fake().closes, fake().opens);
}

ComediSettings with_enable(bool heartbeat = false, bool active_low = false) {
  ComediSettings c = settings();
  c.enable.channel = 3;  // on the digital I/O, subdevice 2 (the first)
  c.enable.heartbeat = heartbeat;
  c.enable.heartbeat_hz = 500.0;  // 1 ms high, 1 ms low
  c.enable.active_low = active_low;
  return c;
}

bool enable_line() { return (fake_comedi::shared().dio.load() & (1u << 3)) != 0; }

TEST_F(ComediBackendTest, TheEnableLineIsAnOutputWrittenEveryTickAfterTheAnalogWrites) {
  ComediBackend b(with_enable(), limits());
  EXPECT_EQ(fake().dio_output, 1u << 3);
  EXPECT_FALSE(enable_line());
  const auto& first = fake().lists.front();  // the safe list: the outputs, then the enable inactive
  ASSERT_EQ(fake().lists.back().n_insns, 2u);
  EXPECT_EQ(fake().lists.back().insns[1].subdev, 2u);
  EXPECT_EQ(fake().lists.back().insns[1].chanspec, CR_PACK(3, 0, 0));
  EXPECT_EQ(first.insns[0].subdev, 2u);  // the latch set inactive before the line became an output
  b.step(10.0, 0.0, 1e-4);
  const auto& tick = fake().lists.back();
  ASSERT_EQ(tick.n_insns, 3u);
  EXPECT_EQ(tick.insns[0].subdev, 1u);
  EXPECT_EQ(tick.insns[1].subdev, 2u);
  EXPECT_EQ(tick.insns[2].insn, static_cast<unsigned>(INSN_READ));
  EXPECT_FALSE(enable_line());  // the bridge has not asked
  b.set_output_enabled(true);
  b.step(10.0, 1e-4, 1e-4);
  EXPECT_TRUE(enable_line());
  EXPECT_TRUE(b.enable_active());
  b.set_output_enabled(false);
  b.step(10.0, 2e-4, 1e-4);
  EXPECT_FALSE(enable_line());
  EXPECT_EQ(b.counters().enable_rises.load(), 1u);
  EXPECT_EQ(b.counters().enable_drops.load(), 1u);
}

TEST_F(ComediBackendTest, AnActiveLowEnableIdlesHigh) {
  ComediBackend b(with_enable(false, true), limits());
  EXPECT_TRUE(enable_line());
  b.set_output_enabled(true);
  b.step(0.0, 0.0, 1e-4);
  EXPECT_FALSE(enable_line());
  b.hold_safe(std::array{0.0});
  EXPECT_TRUE(enable_line());
}

TEST_F(ComediBackendTest, AHeartbeatTogglesEveryHalfPeriodOfTheTicksTimeWhileActive) {
  ComediBackend b(with_enable(true), limits());
  b.set_output_enabled(true);
  std::string levels;
  for (int k = 0; k < 40; ++k) {
    b.step(0.0, k * 1e-4, 1e-4);
    levels += enable_line() ? '1' : '0';
  }
  EXPECT_EQ(levels, "1111111111000000000011111111110000000000");
  // Ticks skipped: the phase is the time's, not a count of ticks.
  b.step(0.0, 0.0115, 1e-4);
  EXPECT_FALSE(enable_line());
  b.step(0.0, 0.0125, 1e-4);
  EXPECT_TRUE(enable_line());
  b.set_output_enabled(false);
  for (int k = 0; k < 20; ++k) {
    b.step(0.0, 0.011 + k * 1e-4, 1e-4);
    EXPECT_FALSE(enable_line()) << k;
  }
}

TEST_F(ComediBackendTest, TheEnableDropsOnceTheRampHasReachedTheSafeVoltage) {
  ComediBackend b(with_enable(), limits());
  b.set_output_enabled(true);
  b.step(20.0, 0.0, 1e-4);
  ASSERT_TRUE(enable_line());
  const auto& rec = fake_comedi::shared();
  const std::uint64_t from = rec.events;
  b.hold_safe(std::array{0.0});
  // 20 V in steps of 0.1 V at most (13 DAC counts of 13.1), then the safe list.
  ASSERT_GE(rec.events - from, 201u);
  ASSERT_LE(rec.events - from, 204u);
  for (std::uint64_t i = from; i + 1 < rec.events; ++i) EXPECT_NE(rec.event(i).dio & (1u << 3), 0u) << i;
  EXPECT_EQ(rec.event(rec.events - 2).ao[0], code(0.0, -10, 10));  // there, still enabled
  EXPECT_FALSE(enable_line());
  EXPECT_EQ(b.counters().enable_drops.load(), 1u);
}

TEST_F(ComediBackendTest, AnEnableLineTheCardCannotDriveIsRefusedWithTheOutputSafe) {
  const auto refused = [&](const ComediSettings& c) -> std::string {
    fake_comedi::reset();
    try {
      ComediBackend b(c, limits());
    } catch (const ConfigError& e) {
      EXPECT_EQ(fake().closes, fake().opens);
      EXPECT_EQ(fake().writes, 1);  // the safe voltage, before the refusal
      return e.what();
    }
    return "accepted";
  };
  ComediSettings c = with_enable();
  c.enable.channel = 8;
  std::string r = refused(c);
  EXPECT_TRUE(contains(r, "comedi.enable.channel") && contains(r, "8 channels")) << r;
  c = with_enable();
  c.enable.subdevice = 1;
  r = refused(c);
  EXPECT_TRUE(contains(r, "comedi.enable.subdevice") && contains(r, "not a digital output")) << r;
  c = with_enable();
  c.enable.subdevice = 3;
  EXPECT_TRUE(contains(refused(c), "comedi.enable.subdevice"));
  EXPECT_EQ(refused(with_enable()), "accepted");
}

TEST_F(ComediBackendTest, AConfigTheCardRefusesAfterOpeningLeavesTheOutputSafe) {
  const auto refused = [&](const ComediSettings& c, const ActuatorLimits& a) -> std::string {
    fake_comedi::reset();
    try {
      ComediBackend b(c, a);
    } catch (const ConfigError& e) {
      EXPECT_EQ(fake().closes, fake().opens) << "the device stays open";
      return e.what();
    }
    return "accepted";
  };
  ComediSettings c = settings();
  c.amplifier_gain_V_per_V = 20.0;  // +-250 V needs +-12.5 V: the DAC has +-10 V
  std::string r = refused(c, limits(10.0));
  EXPECT_TRUE(contains(r, "comedi.ao.range")) << r;
  EXPECT_TRUE(contains(r, "[-12.5, 12.5] V")) << r;
  EXPECT_EQ(fake().writes, 1);
  EXPECT_EQ(fake().last_write, code(0.5, -10, 10));  // 10 V / 20 written before the refusal
  c = settings();
  c.ai.channel = 16;
  r = refused(c, limits());
  EXPECT_TRUE(contains(r, "comedi.ai.channel")) << r;
  EXPECT_EQ(fake().writes, 1);
  c = settings();
  c.ai.range = 3;
  EXPECT_TRUE(contains(refused(c, limits()), "comedi.ai.range"));
  c = settings();
  c.ai.subdevice = 2;  // the digital I/O
  EXPECT_TRUE(contains(refused(c, limits()), "comedi.ai.subdevice"));
  EXPECT_EQ(fake().writes, 1);
  c = settings();
  c.ao.range = 1;  // [0, 10] V cannot go negative
  EXPECT_TRUE(contains(refused(c, limits()), "comedi.ao.range"));
  c = settings();
  c.ao.channel = static_cast<int>(fake_comedi::kAoChannels);  // no usable output: nothing is written
  EXPECT_TRUE(contains(refused(c, limits()), "comedi.ao.channel"));
  EXPECT_EQ(fake().writes, 0);
  c = settings();
  c.ao.subdevice = -1;  // auto: the first of each kind
  c.ai.subdevice = -1;
  EXPECT_EQ(refused(c, limits()), "accepted");
  c.calibration = "/no/such/file";
  EXPECT_TRUE(contains(refused(c, limits()), "comedi.calibration"));
}

TEST_F(ComediBackendTest, ADeviceThatDoesNotOpenIsARuntimeFailure) {
  fake().open_fails = true;
  EXPECT_THROW(ComediBackend(settings(), limits()), std::runtime_error);
  BridgeSettings s;
  s.backend = "comedi";
  s.comedi = settings();
  s.comedi.device = "/dev/nothing";
  fake().open_fails = false;
  EXPECT_THROW(make_stage_backend(s), std::runtime_error);
  s.comedi.device = "/dev/comedi0";
  EXPECT_EQ(make_stage_backend(s)->name(), "comedi");
}

}  // namespace
}  // namespace hystloop
