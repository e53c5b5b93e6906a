// hystloop-bridge's configuration: defaults are the papers' and the issue's, every value is
// validated where it enters and a refusal names the field; the servo, the block size and the
// wake-up batching are the bridge's now; every deployed config loads; the report
// handoff between the real-time and the I/O thread; the send-time ring behind the latency figures.
#include <array>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>
#include <thread>

#include "bridge/bridge_settings.hpp"
#include "bridge/rt_report.hpp"
#include "core/send_time_ring.hpp"
#include "bridge/stage_backend.hpp"
#include "models/model_descriptors.hpp"
#include "support/allocation_counter.hpp"
#include "support/text.hpp"

namespace hystloop {
namespace {

const std::string kConfigDir = std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/";

std::string refusal(const std::string& yaml) {
  try {
    load_bridge_settings(Config::from_string(yaml, "bridge.yaml"));
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "accepted";
}

using testing::contains;

TEST(BridgeSettings, DefaultsWithoutAConfig) {
  const BridgeSettings s = load_bridge_settings(Config());
  EXPECT_EQ(s.backend, "sim");
  EXPECT_EQ(s.rate_hz, 10000.0);
  EXPECT_EQ(s.dt_s(), 1e-4);
  EXPECT_EQ(s.stage.noise_rms_m, 1e-9);
  EXPECT_EQ(s.limits.u_min_V, -250.0);
  EXPECT_EQ(s.limits.u_max_V, 250.0);
  EXPECT_EQ(s.limits.watchdog_s, 2e-3);
  EXPECT_EQ(s.stage.banning.hysteresis.a, 8.58e-9);  // Table 1
  EXPECT_EQ(s.stage.banning.stage.k, 1.17e8);        // Table 2
  EXPECT_FALSE(s.auto_arm);
  // Blocks of 50 ticks (200 HX_SENSOR messages a second); the clock wakes every tick; LCM queues
  // 256 command blocks.
  EXPECT_EQ(s.block_ticks, 50);
  EXPECT_EQ(s.rt.ticks_per_wake, 1);
  EXPECT_EQ(s.command_queue_capacity, 256);
  // Without a config the servo is off (feedforward only); its anti-windup limit is the range.
  EXPECT_FALSE(s.servo.enabled());
  EXPECT_EQ(s.servo.kp, 0.0);
  EXPECT_EQ(s.servo.ki, 0.0);
  EXPECT_EQ(s.servo.kd, 0.0);
  EXPECT_GT(s.servo.nominal_gain_m_per_V, 0.0);
  EXPECT_EQ(s.servo.d_filter_hz, 1000.0);
  EXPECT_EQ(s.servo.u_min_V, -250.0);
  EXPECT_EQ(s.servo.u_max_V, 250.0);
}

TEST(BridgeSettings, TheServoTakesItsGainsFromServoKeysAndItsLimitFromTheActuatorsRange) {
  const BridgeSettings s = load_bridge_settings(
      Config::from_string("servo: {kp: 0.2, ki: 300, kd: 1.0e-5, nominal_gain_m_per_V: 6.0e-9, d_filter_hz: 500}\n"
                          "actuator: {u_min_V: -100, u_max_V: 200}",
                          "bridge.yaml"));
  EXPECT_EQ(s.servo.kp, 0.2);
  EXPECT_EQ(s.servo.ki, 300.0);
  EXPECT_EQ(s.servo.kd, 1e-5);
  EXPECT_EQ(s.servo.nominal_gain_m_per_V, 6e-9);
  EXPECT_EQ(s.servo.d_filter_hz, 500.0);
  EXPECT_EQ(s.servo.u_min_V, -100.0);
  EXPECT_EQ(s.servo.u_max_V, 200.0);
  EXPECT_TRUE(s.servo.enabled());
  EXPECT_FALSE(s.servo.has_notch());  // none unless asked for
  const auto lines = describe(s);
  EXPECT_TRUE(
      std::any_of(lines.begin(), lines.end(), [](const std::string& l) { return contains(l, "servo: kp 0.2"); }));
  // A notch, designed for the bridge's own clock.
  const BridgeSettings n = load_bridge_settings(
      Config::from_string("bridge: {rate_hz: 20000}\nservo: {ki: 300, notch_hz: 1500, notch_q: 3}", "bridge.yaml"));
  EXPECT_EQ(n.servo.notch_hz, 1500.0);
  EXPECT_EQ(n.servo.notch_q, 3.0);
  EXPECT_EQ(n.servo.tick_rate_hz, 20000.0);
  const auto notch_lines = describe(n);
  EXPECT_TRUE(std::any_of(notch_lines.begin(), notch_lines.end(),
                          [](const std::string& l) { return contains(l, "notch at 1500 Hz (Q 3)"); }));
}

TEST(BridgeSettings, TheDeployConfigIsValidAndComplete) {
  const Config c = Config::load_file(kConfigDir + "bridge.yaml");
  const BridgeSettings s = load_bridge_settings(c);
  EXPECT_EQ(s.limits.slew_V_per_s, 5e4);
  EXPECT_EQ(s.limits.watchdog_s, 2e-3);
  EXPECT_EQ(s.block_ticks, 50);
  EXPECT_GE(s.rt.ticks_per_wake, 1);
  EXPECT_LE(s.rt.ticks_per_wake, s.block_ticks);
  EXPECT_EQ(s.command_queue_capacity, 256);
  EXPECT_EQ(s.servo.kp, 0.05);
  EXPECT_EQ(s.servo.ki, 2000.0);  // with the notch at the resonance (bridge_servo_margins_test)
  EXPECT_EQ(s.servo.kd, 0.0);
  EXPECT_EQ(s.servo.nominal_gain_m_per_V, 6.3e-9);
  EXPECT_EQ(s.servo.d_filter_hz, 1000.0);
  EXPECT_EQ(s.servo.notch_hz, 1720.0);
  EXPECT_EQ(s.servo.notch_q, 0.7);
  EXPECT_EQ(s.servo.tick_rate_hz, s.rate_hz);
  // Every key the bridge reads is documented there (axis y's and z's own actuator, servo and comedi
  // keys in a comment: a one-axis stage refuses them)...
  const auto per_axis_comedi = [](const std::string& key) {
    return key.starts_with("comedi.y.") || key.starts_with("comedi.z.");
  };
  const auto per_axis = [&](const std::string& key) {
    return key.starts_with("actuator.y.") || key.starts_with("actuator.z.") || key.starts_with("servo.y.") ||
           key.starts_with("servo.z.") || per_axis_comedi(key);
  };
  for (const std::string& key : bridge_config_keys()) {
    if (!per_axis(key)) {
      EXPECT_TRUE(c.has(key)) << key << " is not documented";
    }
  }
  // ... and every key listed is really read: a value of the wrong kind is refused by name.
  for (const std::string& key : bridge_config_keys()) {
    Config bad(c);
    if (per_axis(key)) bad.apply_override("bridge.axes=3");
    if (per_axis_comedi(key)) {  // read by the card's backend: three axes, each on its own channels
      for (const char* set : {"bridge.backend=comedi", "rt.ticks_per_wake=1", "comedi.y.ao.channel=1",
                              "comedi.y.ai.channel=1", "comedi.z.ao.channel=2", "comedi.z.ai.channel=2"}) {
        bad.apply_override(set);
      }
    }
    bad.apply_override(key + "=[1, 2]");
    std::string what = "accepted";
    try {
      load_bridge_settings(bad);
    } catch (const ConfigError& e) {
      what = e.what();
    }
    EXPECT_TRUE(contains(what, key)) << key << ": " << what;
  }
}

TEST(BridgeSettings, EveryDeployedBridgeConfigLoads) {
  const BridgeSettings demo = load_bridge_settings(Config::load_file(kConfigDir + "demo/bridge.yaml"));
  EXPECT_EQ(demo.stage.drift_fraction, 0.10);
  EXPECT_EQ(demo.limits.watchdog_s, 2e-3);
  EXPECT_EQ(demo.servo.kp, 0.1);
  EXPECT_EQ(demo.servo.ki, 600.0);
  EXPECT_EQ(demo.servo.nominal_gain_m_per_V, 6.3e-9);
  EXPECT_EQ(demo.oscillation.rms_V, 1.0);
  EXPECT_EQ(demo.oscillation.hold_s, 0.02);
  EXPECT_EQ(demo.block_ticks, 50);
  EXPECT_LE(demo.rt.ticks_per_wake, demo.block_ticks);
  EXPECT_TRUE(demo.rt.lock_memory);
  EXPECT_NO_THROW(load_bridge_settings(Config::load_file(kConfigDir + "banning/bridge.yaml")));
}

// A card needs real time unless waived; the simulators do not (their stage has no wall clock).
TEST(BridgeSettings, AHardwareBackendRequiresRealTimeUnlessWaived) {
  const std::string card = "bridge: {backend: comedi}\n";
  const std::string why = refusal(card + "rt: {ticks_per_wake: 1}\n");
  EXPECT_TRUE(contains(why, "bridge.yaml: rt.required: real time is required")) << why;
  EXPECT_TRUE(contains(why, "rt.required: false")) << why;
  EXPECT_TRUE(contains(refusal(card + "rt: {ticks_per_wake: 1, priority: 80, lock_memory: false}\n"), "rt.required"));
  EXPECT_EQ(refusal(card + "rt: {ticks_per_wake: 1, priority: 80, lock_memory: true}\n"), "accepted");
  EXPECT_EQ(refusal(card + "rt: {ticks_per_wake: 1, required: false}\n"), "accepted");
  EXPECT_FALSE(load_bridge_settings(Config()).rt.required);
  EXPECT_TRUE(contains(refusal("rt: {required: true}\n"), "rt.required"));  // asked for on a simulator too
  const BridgeSettings deployed = load_bridge_settings(Config::load_file(kConfigDir + "bridge-comedi.yaml"));
  EXPECT_TRUE(deployed.rt.required);
  EXPECT_TRUE(contains(real_time_refused("SCHED_FIFO priority 80 refused: Operation not permitted"),
                       "setcap cap_sys_nice,cap_ipc_lock+ep"));
}

TEST(BridgeSettings, RefusalsNameTheField) {
  EXPECT_TRUE(contains(refusal("actuator: {watchdog_s: -1}"), "bridge.yaml: actuator.watchdog_s"));
  EXPECT_TRUE(contains(refusal("actuator: {u_min_V: 10, u_max_V: 5}"), "actuator.u_max_V"));
  EXPECT_TRUE(contains(refusal("actuator: {safe_u_V: 300}"), "actuator.safe_u_V"));
  EXPECT_TRUE(contains(refusal("actuator: {watchdog_s: 0.00015}"), "two ticks"));
  EXPECT_TRUE(contains(refusal("actuator: {position_min_m: 1e-6, position_max_m: -1e-6}"), "actuator.position_max_m"));
  EXPECT_TRUE(contains(refusal("actuator: {position_max_m: 5}"), "actuator.position_max_m"));  // beyond 1 m
  EXPECT_TRUE(contains(refusal("bridge: {axes: 2}\nactuator: {y: {position_min_m: 2e-6, position_max_m: 1e-6}}"),
                       "actuator.y.position_max_m"));
  EXPECT_TRUE(contains(refusal("bridge: {backend: daq}"), "bridge.backend"));
  EXPECT_TRUE(contains(refusal("bridge: {oscillation_rms_V: -1}"), "bridge.oscillation_rms_V"));
  EXPECT_TRUE(contains(refusal("bridge: {oscillation_above_hz: 5000}"), "bridge.oscillation_above_hz"));
  EXPECT_TRUE(contains(refusal("bridge: {oscillation_hold_s: 0.001}"), "bridge.oscillation_hold_s"));
  EXPECT_TRUE(contains(refusal("bridge: {noise_rms_m: .nan}"), "bridge.noise_rms_m"));
  EXPECT_TRUE(contains(refusal("banning: {hysteresis: {b: 9.0e-9}}"), "banning.hysteresis.b"));
  EXPECT_TRUE(contains(refusal("banning: {order: sideways}"), "banning.order"));
  EXPECT_TRUE(contains(refusal("ro: {c1: 0}"), "ro.c1"));
  EXPECT_TRUE(contains(refusal("rt: {priority: 50, io_priority: 50}"), "rt.io_priority"));
  EXPECT_TRUE(contains(refusal("actuator: {watchdog: 0.1}"), "did you mean 'actuator.watchdog_s'"));
  EXPECT_EQ(refusal("bridge: {backend: ro, drift_fraction: 0.1}\nrt: {priority: 80, io_priority: 70}"), "accepted");
}

// The simulated stage's banning: section is read through BanningDescriptor's table, the one
// hystloop-identify --model banning writes its YAML from: every key of the table is a config key
// and is taken, a section the table writes loads unchanged, a refusal names the key, and the
// start-up line is the table's summary.
TEST(BridgeSettings, TheBanningSectionIsTheTables) {
  const std::vector<std::string>& keys = bridge_config_keys();
  const BanningStageParams d = load_bridge_settings(Config()).stage.banning;
  for (const auto& row : BanningDescriptor::table()) {
    const std::string key = "banning." + std::string(row.name);
    EXPECT_NE(std::find(keys.begin(), keys.end(), key), keys.end()) << key;
    Config config;
    config.apply_override(key + "=" + row.show(d));
    EXPECT_NO_THROW(load_bridge_settings(config)) << key;
  }
  BanningStageParams p = d;
  p.hysteresis.alpha = 1.2345678901234567e-3;
  p.stage.c = 2.5e3;
  p.order = BanningOrder::kStageThenHysteresis;
  const std::string yaml = yaml_section(BanningDescriptor::name, BanningDescriptor::table(), p);
  const BridgeSettings s = load_bridge_settings(Config::from_string(yaml, "banning.yaml"));
  EXPECT_EQ(yaml_section(BanningDescriptor::name, BanningDescriptor::table(), s.stage.banning), yaml);
  const std::vector<std::string> lines = describe(s);
  EXPECT_NE(std::find(lines.begin(), lines.end(), "banning: " + BanningDescriptor::summary_of(p)), lines.end());
  EXPECT_TRUE(contains(BanningDescriptor::summary_of(p), "hysteresis.alpha 0.00123457 1/V"));
  EXPECT_TRUE(contains(refusal("banning: {hysteresis: {a: 8.58e-9x}}"),
                       "bridge.yaml: banning.hysteresis.a: expected a number, got '8.58e-9x'"));
  EXPECT_TRUE(contains(refusal("banning: {order: sideways}"),
                       "bridge.yaml: banning.order: expected one of hysteresis_then_stage|stage_then_hysteresis"));
  EXPECT_TRUE(contains(refusal("banning: {stage: {k: -1}}"), "bridge.yaml: banning.stage.k: must be > 0"));
  EXPECT_TRUE(contains(refusal("banning: {stage: {m: 1}}"), "banning.stage.m"));
}

// The series plant (bridge.backend series): plant.hysteresis.* and plant.stage.* in the forms a lab
// prints, every refusal naming its key, and the two-mode example loading as its comment says.
TEST(BridgeSettings, TheSeriesPlantsKeys) {
  const BridgeSettings s = load_bridge_settings(Config::from_string(
      "bridge: {backend: series, rate_hz: 20000}\n"
      "plant:\n"
      "  hysteresis: {kind: bouc_wen, bouc_wen: {d: 7.4e-9, beta: 0.006, gamma: 0.002}}\n"
      "  stage:\n"
      "    modes: [{frequency_hz: 780, damping_ratio: 0.03, weight: 0.92}, {frequency_hz: 2400, damping_ratio: 0.02}]\n"
      "    delay_s: 75.0e-6\n",
      "bridge.yaml"));
  EXPECT_EQ(s.backend, "series");
  EXPECT_EQ(s.stage.tick_s, 5e-5);
  EXPECT_EQ(s.stage.hysteresis.kind, HysteresisPlantKind::bouc_wen);
  EXPECT_EQ(s.stage.hysteresis.bouc_wen.d, 7.4e-9);
  EXPECT_EQ(s.stage.hysteresis.bouc_wen.gamma, 0.002);
  EXPECT_EQ(s.stage.hysteresis.bouc_wen.alpha, BoucWenParams{}.alpha);
  ASSERT_EQ(s.stage.linear.form, LinearStageSpec::Form::kModes);
  ASSERT_EQ(s.stage.linear.modes.size(), 2U);
  EXPECT_EQ(s.stage.linear.modes[0].frequency_hz, 780.0);
  EXPECT_EQ(s.stage.linear.modes[0].weight, 0.92);
  EXPECT_EQ(s.stage.linear.modes[1].damping_ratio, 0.02);
  EXPECT_EQ(s.stage.linear.modes[1].weight, 1.0);  // the default
  EXPECT_EQ(s.stage.linear.delay_s, 75e-6);
  const auto lines = describe(s);
  EXPECT_NE(std::find_if(lines.begin(), lines.end(),
                         [](const std::string& l) { return contains(l, "plant: bouc_wen hysteresis"); }),
            lines.end());
  auto backend = make_stage_backend(s);
  EXPECT_TRUE(std::isfinite(backend->step(10.0, 0.0, s.dt_s()).y_m));

  // PI (the baseline of `count` plays) and Katalenic through their tables.
  const BridgeSettings pi = load_bridge_settings(
      Config::from_string("plant: {hysteresis: {kind: pi, pi: {count: 10, range_V: 200}}}", "bridge.yaml"));
  EXPECT_EQ(pi.stage.hysteresis.kind, HysteresisPlantKind::pi);
  EXPECT_EQ(pi.stage.hysteresis.pi.count, 10U);
  EXPECT_EQ(pi.stage.hysteresis.pi.thresholds[9], 180.0);
  const BridgeSettings kat = load_bridge_settings(Config::from_string(
      "plant: {hysteresis: {kind: katalenic, katalenic: {k1: 30, output_shaping: {gain: 4.0e-9}}}}", "bridge.yaml"));
  EXPECT_EQ(kat.stage.hysteresis.katalenic.k1, 30.0);
  EXPECT_EQ(kat.stage.hysteresis.katalenic.output_shaping.gain, 4e-9);

  // Zeros and poles in Hz (a conjugate pair listed once), and a transfer function in s.
  const BridgeSettings zp = load_bridge_settings(Config::from_string(
      "plant: {stage: {zeros_hz: [[-3000, 0]], poles_hz: [[-50, 1000], [-2000, 0]]}}", "bridge.yaml"));
  ASSERT_EQ(zp.stage.linear.form, LinearStageSpec::Form::kZeroPoleGain);
  ASSERT_EQ(zp.stage.linear.poles.size(), 2U);
  EXPECT_EQ(zp.stage.linear.poles[0].imag_hz, 1000.0);
  EXPECT_EQ(zp.stage.linear.zeros[0].real_hz, -3000.0);
  const BridgeSettings tf = load_bridge_settings(
      Config::from_string("plant: {stage: {numerator_s: [1.0e8], denominator_s: [1, 2000, 1.0e8]}}", "bridge.yaml"));
  ASSERT_EQ(tf.stage.linear.form, LinearStageSpec::Form::kTransferFunction);
  EXPECT_EQ(tf.stage.linear.denominator_s.size(), 3U);
  // An XY stage of it: each axis the same plant, its own noise seed.
  const BridgeSettings xy = load_bridge_settings(
      Config::from_string("bridge: {backend: series, axes: 2}\nplant: {stage: {delay_s: 1.5e-4}}", "bridge.yaml"));
  const MultiAxisStageConfig stages = multi_axis_stage(xy);
  EXPECT_EQ(stages.axis[1].plant, PlantKind::kSeries);
  EXPECT_EQ(stages.axis[1].tick_s, xy.dt_s());
  EXPECT_EQ(stages.axis[1].linear.delay_s, 1.5e-4);
  auto xy_backend = make_stage_backend(xy);
  EXPECT_EQ(xy_backend->axes(), 2);
  std::array<StageReading, 2> readings{};
  const std::array<double, 2> u{10.0, -10.0};
  xy_backend->step_axes(u, 0.0, xy.dt_s(), readings);
  EXPECT_TRUE(std::isfinite(readings[0].y_m) && std::isfinite(readings[1].y_m));

  // No stage given: Banning's Table 2.
  const BridgeSettings d = load_bridge_settings(Config());
  EXPECT_EQ(d.stage.hysteresis.kind, HysteresisPlantKind::coleman_hodgdon);
  EXPECT_EQ(d.stage.linear.denominator_s,
            LinearStageSpec::second_order(d.stage.banning.stage.k, d.stage.banning.stage.c).denominator_s);
}

TEST(BridgeSettings, SeriesPlantRefusalsNameTheKey) {
  EXPECT_TRUE(contains(refusal("plant: {hysteresis: {kind: preisach}}"), "bridge.yaml: plant.hysteresis.kind"));
  EXPECT_TRUE(contains(refusal("plant: {hysteresis: {pi: {weights: [1.0e-9, 2.0e-9]}}}"),
                       "plant.hysteresis.pi.weights: unknown key"));  // the baseline only
  EXPECT_TRUE(contains(refusal("plant: {hysteresis: {pi: {count: 0}}}"), "plant.hysteresis.pi.count"));
  EXPECT_TRUE(contains(refusal("plant: {hysteresis: {katalenic: {k1: -1}}}"), "plant.hysteresis.katalenic.k1"));
  EXPECT_TRUE(contains(refusal("plant: {hysteresis: {linear: {gain: 0}}}"), "plant.hysteresis.linear.gain"));
  EXPECT_TRUE(contains(refusal("plant: {hysteresis: {bouc_wen: {gamma: 1.0}}}"), "plant.hysteresis.bouc_wen.gamma"));
  EXPECT_TRUE(
      contains(refusal("plant: {hysteresis: {coleman_hodgdon: {b: 9.0e-9}}}"), "plant.hysteresis.coleman_hodgdon.b"));
  EXPECT_TRUE(contains(refusal("plant: {hysteresis: {mem: {c1: 0}}}"), "plant.hysteresis.mem.c1"));
  EXPECT_TRUE(contains(refusal("plant: {hysteresis: {bouc_wen: {gama: 0.001}}}"),
                       "did you mean 'plant.hysteresis.bouc_wen.gamma'"));
  EXPECT_TRUE(contains(refusal("plant: {stage: {pole_hz: [[-50, 1000]]}}"), "did you mean 'plant.stage.poles_hz'"));
  EXPECT_TRUE(contains(refusal("plant: {stage: {modes: [{frequency_hz: 780, dampin_ratio: 0.03}]}}"),
                       "plant.stage.modes[0].dampin_ratio: unknown key; did you mean 'damping_ratio'"));
  EXPECT_TRUE(contains(refusal("plant: {stage: {modes: [{frequency_hz: 780}]}}"),
                       "plant.stage.modes[0].damping_ratio: required"));
  EXPECT_TRUE(contains(refusal("plant: {stage: {modes: [{frequency_hz: -780, damping_ratio: 0.03}]}}"),
                       "plant.stage.modes[0]"));
  EXPECT_TRUE(contains(refusal("plant: {stage: {poles_hz: [[-50, 1000, 3]]}}"),
                       "plant.stage.poles_hz[0]: expected 2 numbers, got 3"));
  EXPECT_TRUE(contains(refusal("plant: {stage: {poles_hz: [[50, 1000]]}}"), "plant.stage.poles"));
  EXPECT_TRUE(contains(refusal("plant: {stage: {zeros_hz: [[-50, 0]]}}"), "plant.stage.poles_hz: required"));
  EXPECT_TRUE(contains(refusal("plant: {stage: {numerator_s: [1]}}"), "plant.stage.denominator_s: required"));
  EXPECT_TRUE(
      contains(refusal("plant: {stage: {poles_hz: [[-50, 1000]], modes: [{frequency_hz: 780, damping_ratio: 0.03}]}}"),
               "give one form"));
  EXPECT_TRUE(contains(refusal("plant: {stage: {delay_s: 0.01}}"), "plant.stage.delay_s"));  // 100 ticks
  EXPECT_TRUE(contains(refusal("plant: {stage: {delay_s: -1.0e-4}}"), "plant.stage.delay_s"));
  EXPECT_EQ(refusal("bridge: {backend: series}\nplant: {stage: {delay_s: 1.5e-4}}"), "accepted");
}

TEST(BridgeSettings, TheTwoModeExampleIsTheSeriesPlantItDescribes) {
  const BridgeSettings s = load_bridge_settings(Config::load_file(kConfigDir + "two-mode/bridge.yaml"));
  EXPECT_EQ(s.backend, "series");
  EXPECT_EQ(s.stage.noise_rms_m, 1e-9);
  EXPECT_EQ(s.stage.hysteresis.kind, HysteresisPlantKind::coleman_hodgdon);
  EXPECT_EQ(s.stage.hysteresis.coleman_hodgdon.a, ColemanHodgdonParams{}.a);  // Table 1
  EXPECT_EQ(s.stage.hysteresis.coleman_hodgdon.alpha, ColemanHodgdonParams{}.alpha);
  ASSERT_EQ(s.stage.linear.modes.size(), 2U);
  EXPECT_EQ(s.stage.linear.modes[0].frequency_hz, 780.0);
  EXPECT_EQ(s.stage.linear.modes[1].frequency_hz, 2400.0);
  EXPECT_NEAR(s.stage.linear.delay_s / s.dt_s(), 1.5, 1e-12);
  EXPECT_NEAR(std::abs(discretise(s.stage.linear, s.dt_s()).dc_gain()), 1.0, 1e-12);
  // It runs as the bridge runs it.
  auto backend = make_stage_backend(s);
  double y = 0.0;
  for (int k = 0; k < 20000; ++k) y = backend->step(100.0, k * s.dt_s(), s.dt_s()).y_true_m;
  SimulatedStageConfig banning = s.stage;
  banning.plant = PlantKind::kBanning;
  SimulatedStage reference(banning);
  double y_banning = 0.0;
  for (int k = 0; k < 20000; ++k) {
    reference.step(100.0, k * s.dt_s(), s.dt_s());
    y_banning = reference.true_position_m();
  }
  EXPECT_NEAR(y, y_banning, 1e-6 * std::abs(y_banning));  // the same hysteresis, unit DC gain stages
}

TEST(BridgeSettings, ServoBlockAndWakeUpRefusalsNameTheField) {
  EXPECT_TRUE(contains(refusal("servo: {ki: -1}"), "bridge.yaml: servo.ki"));
  EXPECT_TRUE(contains(refusal("servo: {kp: -0.1}"), "bridge.yaml: servo.kp"));
  EXPECT_TRUE(contains(refusal("servo: {kd: -1.0e-6}"), "bridge.yaml: servo.kd"));
  EXPECT_TRUE(contains(refusal("servo: {nominal_gain_m_per_V: 0}"), "bridge.yaml: servo.nominal_gain_m_per_V"));
  EXPECT_TRUE(contains(refusal("servo: {d_filter_hz: 0}"), "bridge.yaml: servo.d_filter_hz"));
  EXPECT_TRUE(contains(refusal("servo: {ki: .inf}"), "servo.ki"));
  EXPECT_TRUE(contains(refusal("bridge: {block_ticks: 0}"), "bridge.yaml: bridge.block_ticks"));
  EXPECT_TRUE(contains(refusal("bridge: {block_ticks: 1001}"), "bridge.yaml: bridge.block_ticks"));
  EXPECT_TRUE(contains(refusal("bridge: {command_queue_capacity: 15}"), "bridge.yaml: bridge.command_queue_capacity"));
  EXPECT_TRUE(contains(refusal("bridge: {command_queue_capacity: 100001}"), "bridge.command_queue_capacity"));
  EXPECT_TRUE(contains(refusal("rt: {ticks_per_wake: 0}"), "bridge.yaml: rt.ticks_per_wake"));
  // A block is published when its last tick has run: a wake-up may not run past it.
  const std::string too_many = refusal("rt: {ticks_per_wake: 51}");  // one more than the default block
  EXPECT_TRUE(contains(too_many, "bridge.yaml: rt.ticks_per_wake")) << too_many;
  EXPECT_TRUE(contains(too_many, "bridge.block_ticks")) << too_many;
  EXPECT_TRUE(contains(refusal("bridge: {block_ticks: 4}\nrt: {ticks_per_wake: 5}"), "rt.ticks_per_wake"));
  // The notch: 0 or below 0.45 x the tick rate (which may come from another section), Q in [0.1, 50].
  EXPECT_TRUE(contains(refusal("servo: {notch_hz: 4500}"), "bridge.yaml: servo.notch_hz"));
  EXPECT_TRUE(contains(refusal("servo: {notch_hz: -1}"), "bridge.yaml: servo.notch_hz"));
  EXPECT_TRUE(contains(refusal("bridge: {rate_hz: 2000}\nservo: {notch_hz: 1720}"), "bridge.yaml: servo.notch_hz"));
  EXPECT_TRUE(contains(refusal("servo: {notch_hz: 1720, notch_q: 0.05}"), "bridge.yaml: servo.notch_q"));
  EXPECT_TRUE(contains(refusal("servo: {notch_q: 60}"), "bridge.yaml: servo.notch_q"));
  EXPECT_EQ(refusal("servo: {notch_hz: 4499, notch_q: 50}"), "accepted");
  // The second notch alike, under its own names, per axis too.
  EXPECT_TRUE(contains(refusal("servo: {notch2_hz: 4500}"), "bridge.yaml: servo.notch2_hz"));
  EXPECT_TRUE(contains(refusal("servo: {notch2_hz: 2400, notch2_q: 0.05}"), "bridge.yaml: servo.notch2_q"));
  EXPECT_EQ(refusal("servo: {notch_hz: 780, notch_q: 0.34, notch2_hz: 2400, notch2_q: 3}"), "accepted");
  // The servo's keys were feedback.* in the compensator: not a bridge key.
  EXPECT_TRUE(contains(refusal("feedback: {kp: 0.1}"), "feedback.kp"));

  EXPECT_EQ(refusal("bridge: {block_ticks: 1}\nrt: {ticks_per_wake: 1}"), "accepted");  // a message per tick
  EXPECT_EQ(refusal("bridge: {block_ticks: 10}\nrt: {ticks_per_wake: 10}"), "accepted");
  EXPECT_EQ(refusal("bridge: {block_ticks: 1000, command_queue_capacity: 100000}"), "accepted");
  EXPECT_EQ(refusal("servo: {kp: 0, ki: 0, kd: 0}"), "accepted");  // off
  const BridgeSettings s = load_bridge_settings(
      Config::from_string("bridge: {block_ticks: 20, command_queue_capacity: 16}\nrt: {ticks_per_wake: 20}", "b.yaml"));
  EXPECT_EQ(s.block_ticks, 20);
  EXPECT_EQ(s.rt.ticks_per_wake, 20);
  EXPECT_EQ(s.command_queue_capacity, 16);
}

// Every stop ramps to actuator.safe_u_V first; how long it may take follows
// from the actuator's keys: the longest ramp (from the range's end farthest from safe_u_V, at
// min(safe_ramp, slew)) plus kStopRampMargin_s.
TEST(BridgeSettings, TheStopRampBoundFollowsTheActuator) {
  const BridgeSettings d = load_bridge_settings(Config::load_file(kConfigDir + "bridge.yaml"));
  EXPECT_DOUBLE_EQ(d.limits.longest_safe_ramp_s(), 0.25);  // 250 V at 1e3 V/s
  EXPECT_DOUBLE_EQ(d.stop_ramp_timeout_s, 0.25 + kStopRampMargin_s);
  const BridgeSettings slow =
      load_bridge_settings(Config::from_string("actuator: {safe_u_V: -50, safe_ramp_V_per_s: 100}", "bridge.yaml"));
  EXPECT_DOUBLE_EQ(slow.stop_ramp_timeout_s, 300.0 / 100.0 + kStopRampMargin_s);  // from +250 V
  const BridgeSettings slew = load_bridge_settings(
      Config::from_string("actuator: {safe_ramp_V_per_s: 1.0e6, slew_V_per_s: 1.0e4}", "bridge.yaml"));
  EXPECT_DOUBLE_EQ(slew.stop_ramp_timeout_s, 250.0 / 1e4 + kStopRampMargin_s);  // never faster than the slew
  bool said = false;
  for (const std::string& line : describe(d))
    said = said ||
           contains(line, "stop: every axis ramps to its safe voltage (the longest ramp at most 0.25 s) within 0.75 s");
  EXPECT_TRUE(said);
}

// The safe-state hook: the simulators have no output stage to hold; it must be callable at any
// time, more than once, without stepping, and leave the simulated stage as it was: a backend
// told to hold safe between its steps reads what an identical one that was not told reads.
TEST(StageBackend, SimulatorsHoldSafeTrivially) {
  BridgeSettings s;
  for (const char* name : {"sim", "ro"}) {
    auto held = make_stage_backend(name, s.stage);
    auto untouched = make_stage_backend(name, s.stage);
    EXPECT_TRUE(held->simulated()) << name;
    held->hold_safe(std::array{0.0});
    for (int k = 0; k < 50; ++k) {
      const double u = 10.0 * std::sin(0.1 * k);
      const double t = 1e-4 * k;
      const StageReading a = held->step(u, t, 1e-4);
      const StageReading b = untouched->step(u, t, 1e-4);
      ASSERT_EQ(a.y_m, b.y_m) << name << ", tick " << k;
      ASSERT_EQ(a.flags, b.flags) << name << ", tick " << k;
      EXPECT_FALSE(a.go_safe) << name;
      held->hold_safe(std::array{k % 2 == 0 ? 0.0 : -5.0});
    }
  }
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
    EXPECT_EQ(r.flags, 4);  // SIMULATED
  }
  EXPECT_THROW(make_stage_backend("daq", s.stage), ParameterError);
}

TEST(RtReport, StartsWithNoDepthMeasured) {
  const RtReport r{};
  EXPECT_EQ(r.min_depth_period, -1);
  EXPECT_EQ(r.min_depth_total, -1);
  EXPECT_EQ(r.last_tick, -1);
  EXPECT_EQ(r.last_trip_tick, -1);
  EXPECT_EQ(r.ticks_caught_up, 0u);
  EXPECT_EQ(r.commands_processed, 0u);
  EXPECT_EQ(r.gain_scale, 1.0);
}

TEST(RtReportExchange, HandsOverWithoutSharingABuffer) {
  RtReportExchange ex;
  std::atomic<bool> stop{false};
  std::thread rt([&] {
    std::uint64_t k = 0;
    while (!stop.load()) {
      ex.current().work.add(static_cast<std::int64_t>(k % 100));
      ++k;
      ex.serve_request([&](RtReport& r) {
        // Everything one fill writes is read together.
        r.core.ticks = k;
        r.last_tick = static_cast<std::int64_t>(k) - 1;
        r.buffer_depth = static_cast<std::int64_t>(k % 300);
        r.min_depth_period = static_cast<std::int64_t>(k % 7);
        r.ticks_caught_up = 2 * k;
        r.commands_processed = 3 * k;
      });
    }
  });
  std::uint64_t seen_ticks = 0, seen_samples = 0;
  for (int round = 0; round < 50; ++round) {
    ex.request();
    const RtReport* r = nullptr;
    while ((r = ex.take()) == nullptr) std::this_thread::yield();
    EXPECT_GE(r->core.ticks, seen_ticks);  // cumulative counters only grow
    EXPECT_EQ(r->last_tick, static_cast<std::int64_t>(r->core.ticks) - 1);
    EXPECT_EQ(r->buffer_depth, static_cast<std::int64_t>(r->core.ticks % 300));
    EXPECT_EQ(r->min_depth_period, static_cast<std::int64_t>(r->core.ticks % 7));
    EXPECT_EQ(r->ticks_caught_up, 2 * r->core.ticks);
    EXPECT_EQ(r->commands_processed, 3 * r->core.ticks);
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
