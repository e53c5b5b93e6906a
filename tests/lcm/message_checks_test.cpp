// The value contract: each fixture is valid, and each way of breaking it is classified
// as non-finite or out-of-range.
#include "lcm/message_checks.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "lcm/message_fixtures.hpp"

namespace hystloop {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(MessageChecks, FixturesAreValid) {
  for (std::int64_t k = 0; k < 12; ++k) {
    EXPECT_EQ(check_message(fixtures::sample(k)), Verdict::kOk) << k;
    EXPECT_EQ(check_message(fixtures::command(k)), Verdict::kOk) << k;
    EXPECT_EQ(check_message(fixtures::trajectory(k)), Verdict::kOk) << k;
    EXPECT_EQ(check_message(fixtures::params(k)), Verdict::kOk) << k;
    EXPECT_EQ(check_message(fixtures::status(k)), Verdict::kOk) << k;
    EXPECT_EQ(check_message(fixtures::control(k)), Verdict::kOk) << k;
  }
}

TEST(MessageChecks, SensorSample) {
  for (double sensor_sample_t::*field : {&sensor_sample_t::u_V, &sensor_sample_t::y_m}) {
    for (double bad : {kNaN, kInf, -kInf}) {
      auto m = fixtures::sample(1);
      m.*field = bad;
      EXPECT_EQ(check_message(m), Verdict::kNonFinite);
    }
  }
  auto m = fixtures::sample(1);
  m.y_m = 1.6;  // micrometres sent as metres... or worse
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::sample(1);
  m.seq = -1;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::sample(1);
  m.flags = 64;  // a reserved bit
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m.flags = -1;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
}

TEST(MessageChecks, NonFiniteOutranksOutOfRange) {
  auto m = fixtures::sample(1);
  m.seq = -5;
  m.u_V = kNaN;
  EXPECT_EQ(check_message(m), Verdict::kNonFinite);
}

TEST(MessageChecks, ActuatorCommand) {
  for (double actuator_command_t::*field :
       {&actuator_command_t::u_V, &actuator_command_t::u_ff_V, &actuator_command_t::u_fb_V}) {
    auto m = fixtures::command(2);
    m.*field = kNaN;
    EXPECT_EQ(check_message(m), Verdict::kNonFinite);
  }
  auto m = fixtures::command(2);
  m.y_ref_m = kNaN;  // "no reference" is a documented sentinel
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.y_ref_m = kInf;
  EXPECT_EQ(check_message(m), Verdict::kNonFinite);
  m = fixtures::command(2);
  m.u_V = 2.0e4;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::command(2);
  m.sample_seq = -1;  // not an answer to a sample: allowed
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.sample_seq = -2;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::command(2);
  m.mode = 6;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
}

TEST(MessageChecks, Trajectory) {
  auto m = fixtures::trajectory(3);
  m.points_y_m[1] = kNaN;
  EXPECT_EQ(check_message(m), Verdict::kNonFinite);
  m = fixtures::trajectory(3);
  std::swap(m.points_t_s[0], m.points_t_s[1]);  // times must increase
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::trajectory(3);
  m.points_t_s.pop_back();  // array shorter than n_points
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::trajectory(3);
  m.shape = trajectory_t::SINE;
  m.frequency_Hz = 0.0;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m.shape = trajectory_t::HOLD;  // a hold needs no frequency
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.shape = 5;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::trajectory(3);
  m.n_points = 0;
  m.points_t_s.clear();
  m.points_y_m.clear();
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);  // POINTS with no point
  m = fixtures::trajectory(3);
  m.version = 0;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::trajectory(3);
  m.amplitude_m = -kInf;
  EXPECT_EQ(check_message(m), Verdict::kNonFinite);
}

TEST(MessageChecks, MemParams) {
  for (double mem_params_t::*field : {&mem_params_t::c1, &mem_params_t::c2, &mem_params_t::c3,
                                      &mem_params_t::residual_m, &mem_params_t::window_s}) {
    auto m = fixtures::params(2);
    m.*field = kNaN;
    EXPECT_EQ(check_message(m), Verdict::kNonFinite);
  }
  auto m = fixtures::params(2);
  m.c1 = 0.0;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::params(2);
  m.c3 = -0.1;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::params(2);
  m.c2 = -1e-12;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::params(2);
  m.c2 = 0.0;  // a purely linear element is a valid set
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.version = 0;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::params(2);
  m.valid = false;  // the consumer's decision, not a wire error
  EXPECT_EQ(check_message(m), Verdict::kOk);
}

TEST(MessageChecks, ServiceStatus) {
  auto m = fixtures::status(3);
  m.loop_p99_us = kNaN;  // "not measured"
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.latency_max_us = kInf;
  EXPECT_EQ(check_message(m), Verdict::kNonFinite);
  m = fixtures::status(3);
  m.counter_values[0] = -1;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::status(3);
  m.process.clear();
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::status(3);
  m.state = 9;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::status(3);
  m.n_counters = 2;  // arrays hold 3
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
}

TEST(MessageChecks, Control) {
  auto m = fixtures::control(1);
  m.ki = kNaN;
  EXPECT_EQ(check_message(m), Verdict::kNonFinite);
  m = fixtures::control(1);
  m.kp = -0.5;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::control(1);
  m.experiment_duration_s = 0.0;  // an experiment needs a duration...
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m.command = control_t::ARM;  // ...an arm request does not
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.command = 0;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::control(1);
  m.request_id = 0;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
}

}  // namespace
}  // namespace hystloop
