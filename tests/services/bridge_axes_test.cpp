// hystloop-bridge with several axes on its one clock: bridge.axes and the simulated XY(Z) stage's
// coupling are validated where they enter (a refusal names the key), the simulators build the
// coupled stage the settings describe, and the real-time thread drives every axis from its own
// commands, arms them together and takes all of them to the safe state when one axis's commands
// stop. Real threads, real time: a few tenths of a second in all.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "bridge/bridge_realtime.hpp"
#include "bridge/bridge_settings.hpp"
#include "bridge/servo_request.hpp"
#include "bridge/stage_backend.hpp"
#include "support/text.hpp"
#include "support/eventually.hpp"

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

using testing::contains;

TEST(BridgeAxes, SettingsTakeTheAxesAndTheCouplingAndNameWhatTheyRefuse) {
  const BridgeSettings one = load_bridge_settings(Config::from_string("bridge: {backend: sim}", "bridge.yaml"));
  EXPECT_EQ(one.axes, 1);
  const BridgeSettings xy =
      load_bridge_settings(Config::from_string("bridge: {axes: 2}\ncoupling: {x_to_y: 0.05, y_to_x: -0.01}", "b.yaml"));
  EXPECT_EQ(xy.axes, 2);
  EXPECT_EQ(xy.coupling(1, 0), 0.05);   // C(y, x): y's reading per metre of x
  EXPECT_EQ(xy.coupling(0, 1), -0.01);  // C(x, y)
  const BridgeSettings xyz = load_bridge_settings(Config::from_string("bridge: {axes: 3}", "bridge.yaml"));
  EXPECT_EQ(xyz.coupling(2, 0), 0.03);  // the default flexure stage: x -> z too
  bool says_axes = false;
  for (const std::string& line : describe(xyz)) says_axes = says_axes || contains(line, "axes: 3");
  EXPECT_TRUE(says_axes);

  EXPECT_TRUE(contains(refusal("bridge: {axes: 4}"), "bridge.axes"));
  EXPECT_TRUE(contains(refusal("bridge: {axes: 0}"), "bridge.axes"));
  // The card drives an axis per channel pair, each named: axis y's has no default.
  EXPECT_TRUE(contains(refusal("bridge: {backend: comedi, axes: 2}"), "bridge.yaml: comedi.y.ao.channel"));
  EXPECT_EQ(refusal("bridge: {backend: comedi, axes: 2}\nrt: {ticks_per_wake: 1, required: false}\n"
                    "comedi: {y: {ao: {channel: 1}, ai: {channel: 1}}}"),
            "accepted");
  EXPECT_TRUE(contains(refusal("bridge: {axes: 2}\ncoupling: {x_to_y: 0.7}"), "coupling.x_to_y"));
  // Each entry allowed, together nearly singular: refused for the whole matrix.
  EXPECT_TRUE(contains(refusal("bridge: {axes: 2}\ncoupling: {x_to_y: 0.5, y_to_x: 1.99}"), "coupling"));
  EXPECT_TRUE(contains(refusal("bridge: {axes: 3}\ncoupling: {x_to_y: -0.5, x_to_z: -0.5, y_to_x: -0.5, y_to_z: "
                               "-0.5, z_to_x: -0.5, z_to_y: -0.5}"),
                       "coupling"));
  EXPECT_EQ(refusal("bridge: {axes: 3, backend: ro}"), "accepted");
}

// Each axis its own actuator and servo where it has keys of its own (actuator.y.*, servo.y.*),
// axis x's otherwise; a refusal names the axis's own key; keys of an axis the stage lacks are refused.
TEST(BridgeAxes, EachAxisHasItsOwnActuatorAndServoWhereItHasKeys) {
  const BridgeSettings s = load_bridge_settings(Config::from_string(
      "bridge: {axes: 3}\nactuator: {u_max_V: 200.0, y: {u_min_V: -30.0, u_max_V: 150.0, safe_u_V: 60.0}}\n"
      "servo: {kp: 0.05, z: {kp: 0.2, notch_hz: 0.0}}",
      "bridge.yaml"));
  EXPECT_EQ(s.limits_of(0).u_max_V, 200.0);
  EXPECT_EQ(s.limits_of(1).u_min_V, -30.0);
  EXPECT_EQ(s.limits_of(1).u_max_V, 150.0);
  EXPECT_EQ(s.limits_of(1).safe_u_V, 60.0);
  EXPECT_EQ(s.limits_of(1).slew_V_per_s, s.limits.slew_V_per_s);  // the rest as x's
  EXPECT_EQ(s.limits_of(2).u_max_V, 200.0);                       // z: as x
  EXPECT_EQ(s.servo_of(0).kp, 0.05);
  EXPECT_EQ(s.servo_of(1).kp, 0.05);        // y's gains are x's ...
  EXPECT_EQ(s.servo_of(1).u_max_V, 150.0);  // ... its anti-windup its own actuator's range
  EXPECT_EQ(s.servo_of(2).kp, 0.2);
  EXPECT_EQ(s.servo_of(2).notch_hz, 0.0);
  EXPECT_EQ(s.servo_of(2).ki, s.servo.ki);
  EXPECT_EQ(s.safe_voltages()[1], 60.0);
  // The stop's bound is the longest axis's ramp: x's from -250 V to 0 V (y's is 90 V at the same rate).
  EXPECT_DOUBLE_EQ(s.longest_safe_ramp_s(), 250.0 / 1e3);
  bool says_y = false, says_z = false;
  for (const std::string& line : describe(s)) {
    says_y = says_y || contains(line, "actuator y: range [-30, 150] V");
    says_z = says_z || contains(line, "servo z: kp 0.2");
  }
  EXPECT_TRUE(says_y);
  EXPECT_TRUE(says_z);

  const BridgeSettings slow = load_bridge_settings(
      Config::from_string("bridge: {axes: 2}\nactuator: {y: {safe_ramp_V_per_s: 100.0}}", "bridge.yaml"));
  EXPECT_DOUBLE_EQ(slow.stop_ramp_timeout_s, 250.0 / 100.0 + kStopRampMargin_s);  // y's ramp is the longest

  const std::string bad_range = refusal("bridge: {axes: 2}\nactuator: {y: {u_min_V: 10.0, u_max_V: 5.0}}");
  EXPECT_TRUE(contains(bad_range, "bridge.yaml: actuator.y.u_max_V")) << bad_range;
  const std::string bad_safe = refusal("bridge: {axes: 2}\nactuator: {y: {u_max_V: 100.0, safe_u_V: 120.0}}");
  EXPECT_TRUE(contains(bad_safe, "actuator.y.safe_u_V")) << bad_safe;
  const std::string bad_gain = refusal("bridge: {axes: 2}\nservo: {y: {kp: 2.5}}");
  EXPECT_TRUE(contains(bad_gain, "bridge.yaml: servo.y.kp: must be <= 2")) << bad_gain;
  const std::string no_z = refusal("bridge: {axes: 2}\nservo: {z: {kp: 0.1}}");
  EXPECT_TRUE(contains(no_z, "servo.z: the stage has 2 axes")) << no_z;
  EXPECT_TRUE(contains(refusal("actuator: {y: {u_max_V: 100.0}}"), "actuator.y: the stage has 1 axis"));
  // One watchdog for the stage: an axis has none of its own.
  EXPECT_TRUE(contains(refusal("bridge: {axes: 2}\nactuator: {y: {watchdog_s: 0.01}}"), "actuator.y.watchdog_s"));
}

// SET_GAINS names its axis, or every axis; all or nothing, the refusal naming the axis's field.
TEST(BridgeAxes, SetGainsSetsTheAxisItNamesOrEveryAxis) {
  const BridgeSettings s =
      load_bridge_settings(Config::from_string("bridge: {axes: 2}\nservo: {kp: 0.05, y: {kp: 0.1}}", "bridge.yaml"));
  const std::array<FeedbackGains, kMaxAxes> in_force = s.axes_servo();
  control_t m{};
  m.command = control_t::SET_GAINS;
  m.kp = 0.3;
  m.ki = std::nan("");
  m.kd = std::nan("");
  m.notch_hz = std::nan("");
  m.notch_q = std::nan("");
  m.axis = 1;
  AxisGainsChange c = requested_axis_gains(in_force, 2, m);
  EXPECT_FALSE(c.set[0]);
  EXPECT_TRUE(c.set[1]);
  EXPECT_EQ(c.gains[0].kp, 0.05);
  EXPECT_EQ(c.gains[1].kp, 0.3);
  m.axis = control_t::EVERY_AXIS;
  m.kp = std::nan("");  // each axis keeps its own kp
  m.ki = 1000.0;
  c = requested_axis_gains(in_force, 2, m);
  EXPECT_TRUE(c.set[0] && c.set[1] && !c.set[2]);
  EXPECT_EQ(c.gains[0].kp, 0.05);
  EXPECT_EQ(c.gains[1].kp, 0.1);
  EXPECT_EQ(c.gains[0].ki, 1000.0);
  EXPECT_EQ(c.gains[1].ki, 1000.0);
  m.axis = 2;
  try {
    requested_axis_gains(in_force, 2, m);
    FAIL() << "axis z taken on a stage of two";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "control.axis");
  }
  m.axis = control_t::EVERY_AXIS;
  m.ki = 1e6;
  try {
    requested_axis_gains(in_force, 2, m);
    FAIL() << "ki 1e6 taken";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "servo.ki");  // x's, the first axis it does not fit
  }
  m.axis = 1;
  try {
    requested_axis_gains(in_force, 2, m);
    FAIL() << "ki 1e6 taken";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "servo.y.ki");
  }
  m.axis = 0;
  m.ki = 1000.0;
  EXPECT_EQ(requested_axis_gains(std::array<FeedbackGains, kMaxAxes>{s.servo}, 1, m).gains[0].ki, 1000.0);
}

TEST(BridgeAxes, TheSimulatorsBuildTheCoupledStageTheSettingsDescribe) {
  for (const char* backend : {"sim", "ro"}) {
    BridgeSettings s;
    s.backend = backend;
    s.axes = 2;
    s.stage.noise_rms_m = 0.0;
    const auto stage = make_stage_backend(s);
    ASSERT_EQ(stage->axes(), 2) << backend;
    EXPECT_TRUE(stage->simulated());
    std::array<StageReading, 2> r{};
    const std::array<double, 2> u{100.0, 0.0};  // x moves, y held at 0 V
    for (int k = 0; k < 2000; ++k) stage->step_axes(u, k * 1e-4, 1e-4, r);
    EXPECT_GT(r[0].y_m, 3e-7) << backend;
    EXPECT_NEAR(r[1].y_m, 0.03 * r[0].y_m, 1e-12 * r[0].y_m) << backend;  // y reads 3 % of x, nothing of its own
    EXPECT_EQ(r[1].y_true_m, r[1].y_m);                                   // no noise: the truth is the reading
    EXPECT_EQ(r[1].flags, 4);                                             // SIMULATED
  }
  BridgeSettings s;
  s.axes = 3;
  s.stage.noise_rms_m = 1e-9;
  const MultiAxisStageConfig c = multi_axis_stage(s);
  EXPECT_EQ(c.axes(), 3);
  EXPECT_EQ(c.axis[0].seed, s.stage.seed);  // each axis its own noise
  EXPECT_EQ(c.axis[2].seed, s.stage.seed + 2);
}

// A two-axis stage that records what each axis was given.
struct AxesRecord {
  std::vector<std::array<double, 2>> u_V;
  std::atomic<std::size_t> steps{0};
};

class TwoAxisRecordingBackend final : public StageBackend {
 public:
  explicit TwoAxisRecordingBackend(AxesRecord& r) : r_(r) { r_.u_V.reserve(1 << 20); }
  StageReading step(double u_V, double, double) noexcept override { return {u_V * 1e-9, 0.0, 4}; }
  int axes() const noexcept override { return 2; }
  void step_axes(std::span<const double> u_V, double, double, std::span<StageReading> out) noexcept override {
    if (r_.u_V.size() < r_.u_V.capacity()) r_.u_V.push_back({u_V[0], u_V[1]});
    r_.steps.fetch_add(1);
    out[0] = {0.0, 0.0, 4};
    out[1] = {0.0, 0.0, 4};
  }
  const std::string& name() const noexcept override { return name_; }
  bool simulated() const noexcept override { return true; }
  void hold_safe(std::span<const double>) noexcept override {}

 private:
  AxesRecord& r_;
  std::string name_ = "recording-xy";
};

using testing::eventually;

BridgeSettings two_axes() {
  BridgeSettings s;
  s.axes = 2;
  s.rt.ticks_per_wake = 20;
  s.block_ticks = 20;
  s.auto_arm = true;
  s.limits.safe_ramp_V_per_s = 1e4;  // 1 V per tick
  s.limits.watchdog_s = 2e-3;        // 20 ticks
  s.stop_ramp_timeout_s = 2.0;
  s.max_lead_s = 0.5;  // every command below is taken: x still has hundreds buffered when y's run out
  return s;
}

TEST(BridgeAxes, EveryAxisFollowsItsOwnCommandsAndOneAxisRunningDryTakesBothSafe) {
  const BridgeSettings s = two_axes();
  AxesRecord record;
  BridgeRealtime rt(s, std::make_unique<TwoAxisRecordingBackend>(record));
  ASSERT_EQ(rt.axes(), 2);
  // x gets 4000 ticks of 10 V, y 2000 of -20 V and then non-finite commands, which its core
  // refuses: y's buffer runs dry at tick 2000 while x's holds 2000 more.
  for (std::int64_t k = 0; k < 4000; ++k) {
    const std::array<CommandTick, 2> tick{CommandTick{k, 10.0, std::nan(""), 1, 2},
                                          CommandTick{k, k < 2000 ? -20.0 : std::nan(""), std::nan(""), 1, 2}};
    ASSERT_TRUE(rt.push_commands(tick));
  }
  const CommandTick one_axis{0, 1.0, std::nan(""), 1, 2};
  EXPECT_FALSE(rt.push_command(one_axis)) << "a tick of one axis on a stage of two is refused";
  rt.start();
  ASSERT_TRUE(eventually([&] { return record.steps.load() > 3000; }));
  // Samples carry both axes.
  const auto out = rt.pop_tick();
  ASSERT_TRUE(out.has_value());
  EXPECT_EQ(out->axes, 2);
  rt.stop();

  // Both axes reached their commands (the slew limit: 5 V per tick) ...
  std::size_t both_there = record.u_V.size();
  for (std::size_t i = 0; i < record.u_V.size(); ++i) {
    if (record.u_V[i][0] == 10.0 && record.u_V[i][1] == -20.0) {
      both_there = i;
      break;
    }
  }
  ASSERT_LT(both_there, record.u_V.size()) << "the axes never both reached their commands";
  // ... then y ran dry, and x, with commands left, left its 10 V on the same tick as y its -20 V.
  std::size_t x_left = 0, y_left = 0;
  for (std::size_t i = both_there; i < record.u_V.size() && (x_left == 0 || y_left == 0); ++i) {
    if (x_left == 0 && record.u_V[i][0] != 10.0) x_left = i;
    if (y_left == 0 && record.u_V[i][1] != -20.0) y_left = i;
  }
  ASSERT_GT(y_left, 0u) << "y never left its command";
  EXPECT_EQ(x_left, y_left) << "one safe state: both axes ramp from the same tick";
  EXPECT_LT(x_left, 2100u) << "x left its command when y ran dry, not when its own commands ended";
  EXPECT_NEAR(record.u_V[y_left][0], 9.0, 1e-12);  // the ramp: 1 V per tick towards 0 V
  EXPECT_NEAR(record.u_V[y_left][1], -19.0, 1e-12);
  EXPECT_EQ(record.u_V.back()[0], 0.0);
  EXPECT_EQ(record.u_V.back()[1], 0.0);
}

TEST(BridgeAxes, AStageArmsOnlyWhenEveryAxisHasCommands) {
  const BridgeSettings s = two_axes();
  AxesRecord record;
  BridgeRealtime rt(s, std::make_unique<TwoAxisRecordingBackend>(record));
  // y's commands are all refused (non-finite): y never has one buffered, so auto-arm never arms.
  for (std::int64_t k = 0; k < 3000; ++k) {
    const std::array<CommandTick, 2> tick{CommandTick{k, 10.0, std::nan(""), 1, 2},
                                          CommandTick{k, std::nan(""), std::nan(""), 1, 2}};
    ASSERT_TRUE(rt.push_commands(tick));
  }
  rt.start();
  ASSERT_TRUE(eventually([&] { return record.steps.load() > 1000; }));
  rt.stop();
  for (const auto& u : record.u_V) ASSERT_EQ(u[0], 0.0) << "x moved although y had no commands: never armed";
}

// Each axis clamps to its own actuator's range and ramps to its own safe voltage, at its own rate.
TEST(BridgeAxes, EachAxisKeepsToItsOwnActuator) {
  BridgeSettings s = two_axes();
  ActuatorLimits y = s.limits;
  y.u_min_V = -5.0;
  y.u_max_V = 15.0;
  y.safe_u_V = 5.0;
  y.safe_ramp_V_per_s = 5e3;  // 0.5 V per tick
  s.axis_limits[1] = y;
  s.axis_servo[1] = s.servo;
  s.axis_servo[1]->u_min_V = y.u_min_V;
  s.axis_servo[1]->u_max_V = y.u_max_V;
  AxesRecord record;
  BridgeRealtime rt(s, std::make_unique<TwoAxisRecordingBackend>(record));
  for (std::int64_t k = 0; k < 2000; ++k) {
    const std::array<CommandTick, 2> tick{CommandTick{k, 10.0, std::nan(""), 1, 2},
                                          CommandTick{k, 20.0, std::nan(""), 1, 2}};
    ASSERT_TRUE(rt.push_commands(tick));
  }
  rt.start();
  ASSERT_TRUE(eventually([&] { return record.steps.load() > 2300; }));
  rt.stop();
  double y_max = -1e9;
  for (const auto& u : record.u_V) y_max = std::max(y_max, u[1]);
  EXPECT_EQ(y_max, 15.0) << "y is clamped to its own range, not x's 250 V";
  std::size_t ran_dry = 0;  // the first tick after the commands: both ramp
  for (std::size_t i = 1; i < record.u_V.size() && ran_dry == 0; ++i) {
    if (record.u_V[i - 1][0] == 10.0 && record.u_V[i][0] != 10.0) ran_dry = i;
  }
  ASSERT_GT(ran_dry, 0u);
  EXPECT_NEAR(record.u_V[ran_dry][0], 9.0, 1e-12);   // x: 1 V per tick towards 0 V
  EXPECT_NEAR(record.u_V[ran_dry][1], 14.5, 1e-12);  // y: 0.5 V per tick towards 5 V
  EXPECT_EQ(record.u_V.back()[0], 0.0);
  EXPECT_EQ(record.u_V.back()[1], 5.0);
  EXPECT_EQ(rt.safe_voltages()[1], 5.0);
}

TEST(BridgeAxes, ABackendOfAnotherAxisCountIsRefused) {
  BridgeSettings s = two_axes();
  s.axes = 3;
  AxesRecord record;
  EXPECT_THROW(BridgeRealtime(s, std::make_unique<TwoAxisRecordingBackend>(record)), ParameterError);
}

}  // namespace
}  // namespace hystloop
