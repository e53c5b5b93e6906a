// The value contract: each fixture is valid, and each way of breaking it is classified
// as non-finite or out-of-range.
#include "lcm/message_checks.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <vector>

#include "lcm/message_fixtures.hpp"

namespace hystloop {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(MessageChecks, FixturesAreValid) {
  for (std::int64_t k = 0; k < 12; ++k) {
    EXPECT_EQ(check_message(fixtures::sensor_block(k)), Verdict::kOk) << k;
    EXPECT_EQ(check_message(fixtures::command_block(k)), Verdict::kOk) << k;
    EXPECT_EQ(check_message(fixtures::trajectory(k)), Verdict::kOk) << k;
    EXPECT_EQ(check_message(fixtures::params(k)), Verdict::kOk) << k;
    EXPECT_EQ(check_message(fixtures::status(k)), Verdict::kOk) << k;
    EXPECT_EQ(check_message(fixtures::control(k)), Verdict::kOk) << k;
  }
}

using SensorArray = std::vector<double> sensor_block_t::*;
using CommandArray = std::vector<double> command_block_t::*;

TEST(MessageChecks, SensorBlockRejectsANonFiniteValueAtAnyTick) {
  for (SensorArray field :
       {&sensor_block_t::u_V, &sensor_block_t::u_ff_V, &sensor_block_t::u_fb_V, &sensor_block_t::y_m}) {
    for (double bad : {kNaN, kInf, -kInf}) {
      for (std::size_t tick : {0u, 4u, 9u}) {
        auto m = fixtures::sensor_ticks(100, 10);
        (m.*field)[tick] = bad;
        EXPECT_EQ(check_message(m), Verdict::kNonFinite) << tick;
      }
    }
  }
}

TEST(MessageChecks, SensorBlockAllowsANaNReferenceButNoInfiniteOne) {
  auto m = fixtures::sensor_ticks(100, 10);
  m.y_ref_m.assign(10, kNaN);  // "no reference": an experiment, or no command yet
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.y_ref_m[6] = kInf;
  EXPECT_EQ(check_message(m), Verdict::kNonFinite);
  m.y_ref_m[6] = 2.0;  // metres, not micrometres
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
}

TEST(MessageChecks, SensorBlockRangesAndFlags) {
  auto m = fixtures::sensor_ticks(100, 10);
  m.y_m[3] = 1.6;  // micrometres sent as metres... or worse
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::sensor_ticks(100, 10);
  m.u_fb_V[9] = -2.0e4;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::sensor_ticks(100, 10);
  m.seq = -1;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::sensor_ticks(100, 10);
  m.utime = -1;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::sensor_ticks(100, 10);
  m.buffer_depth_ticks = -1;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m.buffer_depth_ticks = 0;  // the next tick will be late: a fact, not an error
  EXPECT_EQ(check_message(m), Verdict::kOk);
  for (double bad_dt : {0.0, -1e-4, 2.0}) {
    m = fixtures::sensor_ticks(100, 10);
    m.dt_s = bad_dt;
    EXPECT_EQ(check_message(m), Verdict::kOutOfRange) << bad_dt;
  }
  m.dt_s = kNaN;
  EXPECT_EQ(check_message(m), Verdict::kNonFinite);
  m = fixtures::sensor_ticks(100, 10);
  m.flags[7] = 64;  // a reserved bit
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m.flags[7] = -1;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m.flags[7] = 63;  // every known bit
  EXPECT_EQ(check_message(m), Verdict::kOk);
}

TEST(MessageChecks, SensorBlockTickCountAndArraySizesMustAgree) {
  auto m = fixtures::sensor_ticks(0, sensor_block_t::MAX_TICKS);
  EXPECT_EQ(check_message(m), Verdict::kOk);
  // append_tick refuses a tick past MAX_TICKS: told one fewer it appends one, then the count is set back.
  --m.n_ticks;
  ASSERT_TRUE(append_tick(m, sensor_tick(m, 0)));
  m.n_ticks += 1;
  ASSERT_EQ(m.u_V.size(), static_cast<std::size_t>(sensor_block_t::MAX_TICKS) + 1);
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::sensor_ticks(0, 0);  // a block of no tick
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::sensor_ticks(0, 1);
  EXPECT_EQ(check_message(m), Verdict::kOk);
  for (SensorArray field : {&sensor_block_t::u_V, &sensor_block_t::u_ff_V, &sensor_block_t::u_fb_V,
                            &sensor_block_t::y_ref_m, &sensor_block_t::y_m}) {
    m = fixtures::sensor_ticks(0, 10);
    (m.*field).pop_back();
    EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
    (m.*field).push_back(1e-7);
    (m.*field).push_back(1e-7);
    EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  }
  m = fixtures::sensor_ticks(0, 10);
  m.flags.pop_back();
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::sensor_ticks(0, 10);
  m.n_ticks = 9;  // arrays hold 10
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m.n_ticks = -10;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
}

TEST(MessageChecks, NonFiniteOutranksOutOfRange) {
  auto m = fixtures::sensor_block(1);
  m.seq = -5;
  m.u_V[0] = kNaN;
  EXPECT_EQ(check_message(m), Verdict::kNonFinite);
}

TEST(MessageChecks, CommandBlockRejectsANonFiniteFeedforwardAtAnyTick) {
  for (double bad : {kNaN, kInf, -kInf}) {
    for (std::size_t tick : {0u, 5u, 9u}) {
      auto m = fixtures::command_ticks(200, 10, 150);
      m.u_ff_V[tick] = bad;
      EXPECT_EQ(check_message(m), Verdict::kNonFinite) << tick;
    }
  }
  auto m = fixtures::command_ticks(200, 10, 150);
  m.y_ref_m.assign(10, kNaN);  // "no reference" is a documented sentinel
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.y_ref_m[2] = -kInf;
  EXPECT_EQ(check_message(m), Verdict::kNonFinite);
  m = fixtures::command_ticks(200, 10, 150);
  m.u_ff_V[1] = 2.0e4;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
}

TEST(MessageChecks, CommandBlockModesVersionsAndSequence) {
  auto m = fixtures::command_ticks(200, 10, 150);
  m.sample_seq = -1;  // not an answer to a sample yet: allowed
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.sample_seq = -2;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::command_ticks(200, 10, 150);
  m.seq = -1;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::command_ticks(200, 10, 150);
  m.utime = -1;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  for (const std::int8_t mode :
       {command_block_t::MODE_OFF, command_block_t::MODE_LINEAR, command_block_t::MODE_MEM, command_block_t::MODE_PI,
        command_block_t::MODE_KATALENIC, command_block_t::MODE_EXPERIMENT}) {
    m = fixtures::command_ticks(200, 10, 150);
    m.mode[9] = mode;
    EXPECT_EQ(check_message(m), Verdict::kOk) << int{mode};
  }
  for (const std::int8_t bad : {std::int8_t{100}, std::int8_t{-1}, std::int8_t{127}}) {  // numbers no mode has
    m = fixtures::command_ticks(200, 10, 150);
    m.mode[9] = bad;
    EXPECT_EQ(check_message(m), Verdict::kOutOfRange) << int{bad};
  }
  m = fixtures::command_ticks(200, 10, 150);
  m.params_version[4] = 0;  // no identified model
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.params_version[4] = -1;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
}

TEST(MessageChecks, CommandBlockTickCountAndArraySizesMustAgree) {
  auto m = fixtures::command_ticks(0, command_block_t::MAX_TICKS, 0);
  EXPECT_EQ(check_message(m), Verdict::kOk);
  --m.n_ticks;  // as above: one tick past MAX_TICKS
  ASSERT_TRUE(append_tick(m, command_tick(m, 0)));
  m.n_ticks += 1;
  ASSERT_EQ(m.u_ff_V.size(), static_cast<std::size_t>(command_block_t::MAX_TICKS) + 1);
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::command_ticks(0, 0, 0);
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  for (CommandArray field : {&command_block_t::u_ff_V, &command_block_t::y_ref_m}) {
    m = fixtures::command_ticks(0, 10, 0);
    (m.*field).pop_back();
    EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  }
  m = fixtures::command_ticks(0, 10, 0);
  m.params_version.push_back(3);
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::command_ticks(0, 10, 0);
  m.mode.pop_back();
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::command_ticks(0, 10, 0);
  m.n_ticks = 11;  // arrays hold 10
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
  for (double mem_params_t::*field :
       {&mem_params_t::c1, &mem_params_t::c2, &mem_params_t::c3, &mem_params_t::residual_m, &mem_params_t::window_s}) {
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
  // The upper bounds are MEM's descriptor's, as on HX_MODEL: c1 up to 1 m/V, c3 up to 50.
  m = fixtures::params(2);
  m.c1 = 1.5;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m.c1 = 1.0;
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.c3 = 60.0;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m.c3 = 50.0;
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m = fixtures::params(2);
  m.c2 = 0.0;  // a purely linear element is a valid set
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.version = 0;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::params(2);
  for (const std::int64_t id : {std::int64_t{0}, std::int64_t{-7}, std::numeric_limits<std::int64_t>::min()}) {
    m.publisher_id = id;  // any value names a publisher (0 = unknown): the receiver's table, not a wire error
    EXPECT_EQ(check_message(m), Verdict::kOk) << id;
  }
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
  m.ki = kNaN;  // NaN: keep the gain in force
  m.notch_hz = kNaN;
  m.notch_q = kNaN;
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.ki = std::numeric_limits<double>::infinity();
  EXPECT_EQ(check_message(m), Verdict::kNonFinite);
  m = fixtures::control(1);
  m.kp = -0.5;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::control(1);
  m.notch_hz = -1.0;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m = fixtures::control(1);
  m.notch2_hz = kNaN;  // the second notch alike
  m.notch2_q = kNaN;
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.notch2_q = -2.0;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m.notch2_q = 2.0;
  m.notch2_hz = std::numeric_limits<double>::infinity();
  EXPECT_EQ(check_message(m), Verdict::kNonFinite);
  m = fixtures::control(1);
  m.command = control_t::RELEASE_PARAMS;  // the last command there is
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.command = control_t::RELEASE_PARAMS + 1;
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
  // An axis, or every axis for a servo's gains only.
  m = fixtures::control(1);
  m.command = control_t::SET_GAINS;
  m.axis = control_t::EVERY_AXIS;
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.axis = 2;
  EXPECT_EQ(check_message(m), Verdict::kOk);
  m.axis = 3;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m.axis = -2;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
  m.command = control_t::START_EXPERIMENT;
  m.axis = control_t::EVERY_AXIS;
  EXPECT_EQ(check_message(m), Verdict::kOutOfRange);
}

// Found by tests/fuzz/fuzz_messages: a string with a NUL inside decodes, but is cut when the
// message is encoded again, so whoever passes it on sends something else than it received.
TEST(MessageChecks, StringsWithANulInsideAreRefused) {
  const std::string with_nul("reident\0@host", 13);
  mem_params_t p = fixtures::params(1);
  p.source = with_nul;
  EXPECT_EQ(check_message(p), Verdict::kOutOfRange);
  service_status_t st = fixtures::status(1);
  st.detail = with_nul;
  EXPECT_EQ(check_message(st), Verdict::kOutOfRange);
  st = fixtures::status(1);
  if (!st.counter_names.empty()) {
    st.counter_names[0] = with_nul;
    EXPECT_EQ(check_message(st), Verdict::kOutOfRange);
  }
  control_t c = fixtures::control(1);
  c.target = with_nul;
  EXPECT_EQ(check_message(c), Verdict::kOutOfRange);
}

TEST(MessageChecks, TickNumbersStayBelowTwoToThe53) {
  sensor_block_t s = fixtures::sensor_block(1);
  s.seq = (std::int64_t{1} << 53) + 1;
  EXPECT_EQ(check_message(s), Verdict::kOutOfRange);
  s.seq = std::int64_t{1} << 53;
  EXPECT_EQ(check_message(s), Verdict::kOk);
  command_block_t c = fixtures::command_block(1);
  c.seq = INT64_MAX;
  EXPECT_EQ(check_message(c), Verdict::kOutOfRange);
}

}  // namespace
}  // namespace hystloop
