// One set of actuator limits per rig: the bridge reports its limits on HX_STATUS as counters
// (lcm/actuator_status.hpp, voltages in mV from -10 kV so that a negative one is a counter >= 0),
// and rig_limits_differ() finds the first of a process's own that the bridge's report gives
// otherwise, naming the key, both values, where the process's came from, the bridge's host and the
// axis. RigCheck's subscription and the exit 2 are tests/integration/rig_limits.sh's.
#include "runtime/rig_check.hpp"

#include <gtest/gtest.h>

#include <string>

#include "core/config.hpp"
#include "lcm/message_checks.hpp"
#include "support/text.hpp"

namespace hystloop {
namespace {

using testing::contains;

// A bridge's report with axes' limits as its status reports them (the bridge's own loop).
service_status_t bridge_report(const std::vector<ActuatorFigures>& axes) {
  service_status_t s{};
  s.process = "bridge";
  s.host = "stage-pc";
  s.pid = 4242;
  s.state = service_status_t::HEALTHY;
  s.loop_p50_us = s.loop_p99_us = s.loop_max_us = s.latency_p50_us = s.latency_p99_us = s.latency_max_us = 0.0;
  for (std::size_t a = 0; a < axes.size(); ++a) {
    for (const ActuatorCounter& c : kActuatorCounters) {
      s.counter_names.push_back(actuator_counter_name(c, static_cast<int>(a)));
      s.counter_values.push_back(static_cast<std::int64_t>(actuator_counter(c, axes[a])));
    }
  }
  s.n_counters = static_cast<std::int32_t>(s.counter_names.size());
  return s;
}

RigLimitsOwn own(int axis, ActuatorFigures limits, bool has_slew = true) {
  RigLimitsOwn o;
  o.axis = axis;
  o.limits = limits;
  o.has_slew = has_slew;
  o.sources.fill("compensator.yaml");
  return o;
}

TEST(ActuatorStatus, LimitsTravelAsCountersAReceiverAcceptsAndComeBackToTheMillivolt) {
  const ActuatorFigures a{-250.0, 150.0, 5e4};
  const service_status_t s = bridge_report({a, {-20.0, 150.0, 1e4}});
  EXPECT_EQ(check_message(s), Verdict::kOk) << "a negative voltage must be a counter >= 0";
  EXPECT_EQ(s.counter_names[0], "actuator_u_min_mV_from_-10kV");
  EXPECT_EQ(s.counter_values[0], 9'750'000);
  EXPECT_EQ(s.counter_names[5], "y_actuator_slew_mV_per_s");
  EXPECT_DOUBLE_EQ(actuator_value(kActuatorCounters[0], s.counter_values[0]), -250.0);
  EXPECT_DOUBLE_EQ(actuator_value(kActuatorCounters[1], s.counter_values[1]), 150.0);
  EXPECT_DOUBLE_EQ(actuator_value(kActuatorCounters[2], s.counter_values[2]), 5e4);
  // The lowest and highest voltages a config accepts.
  EXPECT_EQ(actuator_counter(kActuatorCounters[0], {-1e4, 1e4, 1.0}), 0u);
  EXPECT_EQ(actuator_counter(kActuatorCounters[1], {-1e4, 1e4, 1.0}), 20'000'000u);
}

TEST(RigCheck, TheSameLimitsAgreeAndEachDifferenceNamesBothValuesAndWhereTheyCameFrom) {
  const ActuatorFigures rig{-250.0, 250.0, 5e4};
  const service_status_t report = bridge_report({rig, rig});
  EXPECT_FALSE(rig_limits_differ({own(0, rig), own(1, rig)}, "compensator", report));
  EXPECT_FALSE(rig_limits_differ({own(0, {-250.0, 250.0004, 5e4})}, "compensator", report)) << "below a mV";

  auto d = rig_limits_differ({own(0, rig), own(1, {-250.0, 200.0, 5e4})}, "compensator", report);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->key, "actuator.u_max_V");
  EXPECT_TRUE(contains(d->text(),
                       "actuator.u_max_V: 200 in this compensator's configuration (compensator.yaml), 250 "
                       "at the bridge on stage-pc (pid 4242, axis y)"))
      << d->text();
  d = rig_limits_differ({own(0, {-250.0, 250.0, 1e4})}, "compensator", report);
  ASSERT_TRUE(d);
  EXPECT_TRUE(contains(d->text(), "actuator.slew_V_per_s: 10000 in this compensator's")) << d->text();
  d = rig_limits_differ({own(0, {-25.0, 250.0, 5e4})}, "compensator", report);
  ASSERT_TRUE(d);
  EXPECT_TRUE(contains(d->text(), "actuator.u_min_V: -25 in this compensator's")) << d->text();
  EXPECT_TRUE(contains(d->text(), "-250 at the bridge")) << d->text();
}

TEST(RigCheck, ARangeOnlyProcessIgnoresTheSlewAndAReportWithoutLimitsIsNotAVerdict) {
  const ActuatorFigures rig{-250.0, 250.0, 5e4};
  EXPECT_FALSE(rig_limits_differ({own(0, {-250.0, 250.0, 0.0}, false)}, "reidentifier", bridge_report({rig})));
  EXPECT_TRUE(rig_limits_differ({own(0, {-200.0, 250.0, 0.0}, false)}, "reidentifier", bridge_report({rig})));
  // A bridge that reports no limits (an older one), or not for this axis.
  EXPECT_FALSE(rig_limits_differ({own(0, {-1.0, 1.0, 1.0})}, "compensator", bridge_report({})));
  EXPECT_FALSE(rig_limits_differ({own(2, {-1.0, 1.0, 1.0})}, "compensator", bridge_report({rig, rig})));
}

TEST(RigCheck, ANominalGainFurtherOffTheBridgesThanThePlausibleFactorIsAnotherStages) {
  const ActuatorFigures rig{-250.0, 250.0, 5e4};
  service_status_t report = bridge_report({rig});
  report.counter_names.emplace_back(kNominalGainCounter);
  report.counter_values.push_back(6'300'000);  // 6.3e-9 m/V in fm/V
  report.n_counters = static_cast<std::int32_t>(report.counter_names.size());
  const Config config = Config::from_string("linear: {gain: 6.34e-9}\n", "compensator.yaml");
  const auto with_gain = [&](double gain) {
    return own(0, rig).with_gain(config, gain, 10.0, "compensator.plausible_gain_factor");
  };
  EXPECT_FALSE(rig_limits_differ({with_gain(6.34e-9)}, "compensator", report));  // an identified 6.34 by 6.3
  EXPECT_FALSE(rig_limits_differ({with_gain(6.2e-8)}, "compensator", report));
  const auto d = rig_limits_differ({with_gain(6.5e-7)}, "compensator", report);  // a 100 um stage's
  ASSERT_TRUE(d);
  EXPECT_EQ(d->key, "linear.gain");
  EXPECT_TRUE(contains(d->reason,
                       "6.5e-07 m/V in this compensator's configuration (compensator.yaml), 6.3e-09 m/V "
                       "at the bridge on stage-pc (pid 4242, axis x: servo.nominal_gain_m_per_V)"))
      << d->reason;
  EXPECT_TRUE(rig_limits_differ({with_gain(6.2e-10)}, "compensator", report));
  // Without a gain of its own (NaN), or from a bridge that reports none: not compared.
  EXPECT_FALSE(rig_limits_differ({own(0, rig)}, "compensator", report));
  EXPECT_FALSE(rig_limits_differ({with_gain(6.5e-7)}, "compensator", bridge_report({rig})));
}

TEST(RigCheck, EachLimitNamesTheFileOrOverrideThatGaveIt) {
  Config config =
      Config::from_string("actuator: {u_min_V: -250, u_max_V: 250, slew_V_per_s: 5.0e4}\n", "compensator.yaml");
  config.layer(Config::from_string("actuator: {u_max_V: 100}\n", "rig.yaml"));
  config.apply_override("actuator.slew_V_per_s=1e4");
  const RigLimitsOwn o = RigLimitsOwn::from(config, 1, {-250.0, 100.0, 1e4}, true);
  EXPECT_EQ(o.axis, 1);
  EXPECT_EQ(o.sources[0], "compensator.yaml");
  EXPECT_EQ(o.sources[1], "rig.yaml");
  EXPECT_EQ(o.sources[2], "--set");
}

}  // namespace
}  // namespace hystloop
