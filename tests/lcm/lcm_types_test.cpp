// Every message type survives encode -> decode with every field intact, and the
// generated constants are the ones the rest of the code relies on.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "lcm/message_fixtures.hpp"
#include "loop/bridge_core.hpp"  // constants only: nothing from hystloop::loop is linked
#include "loop/trajectory.hpp"

namespace hystloop {
namespace {

template <class T>
T round_trip(const T& in) {
  const auto bytes = fixtures::encode(in);
  T out{};
  EXPECT_EQ(out.decode(bytes.data(), 0, static_cast<int>(bytes.size())), static_cast<int>(bytes.size()));
  EXPECT_EQ(fixtures::encode(out), bytes);  // byte-identical re-encoding: no field lost
  return out;
}

TEST(LcmTypes, SensorBlockRoundTripsEveryFieldAndTick) {
  const auto in = fixtures::sensor_block(7);  // 8 ticks
  const auto out = round_trip(in);
  EXPECT_EQ(out.utime, in.utime);
  EXPECT_EQ(out.seq, 70);
  EXPECT_EQ(out.dt_s, in.dt_s);
  EXPECT_EQ(out.buffer_depth_ticks, in.buffer_depth_ticks);
  ASSERT_EQ(out.n_ticks, 8);
  EXPECT_EQ(out.u_V, in.u_V);
  EXPECT_EQ(out.u_ff_V, in.u_ff_V);
  EXPECT_EQ(out.u_fb_V, in.u_fb_V);
  EXPECT_TRUE(std::isnan(out.y_ref_m[4]));  // tick 74: no reference
  EXPECT_EQ(out.y_ref_m[3], in.y_ref_m[3]);
  EXPECT_EQ(out.y_m, in.y_m);
  EXPECT_EQ(out.flags, in.flags);
}

TEST(LcmTypes, CommandBlockRoundTripsEveryFieldAndTick) {
  const auto in = fixtures::command_block(11);  // 5 ticks from 610, answering tick 111
  const auto out = round_trip(in);
  EXPECT_EQ(out.utime, in.utime);
  EXPECT_EQ(out.seq, 610);
  EXPECT_EQ(out.sample_seq, 111);
  ASSERT_EQ(out.n_ticks, 5);
  EXPECT_EQ(out.u_ff_V, in.u_ff_V);
  EXPECT_TRUE(std::isnan(out.y_ref_m[1]));  // tick 611: no reference
  for (std::size_t i : {0u, 2u, 3u, 4u}) EXPECT_EQ(out.y_ref_m[i], in.y_ref_m[i]);
  EXPECT_EQ(out.params_version, in.params_version);
  EXPECT_EQ(out.mode, in.mode);
  EXPECT_EQ(out.mode[0], command_block_t::MODE_KATALENIC);
}

TEST(LcmTypes, ABlockOfOneTickRoundTrips) {
  const auto s = round_trip(fixtures::sensor_ticks(5, 1));
  EXPECT_EQ(s.n_ticks, 1);
  EXPECT_EQ(s.u_V.size(), 1u);
  const auto c = round_trip(fixtures::command_ticks(5, 1, -1));
  EXPECT_EQ(c.n_ticks, 1);
  EXPECT_EQ(c.sample_seq, -1);
}

TEST(LcmTypes, TheLargestBlocksRoundTrip) {
  const auto s = round_trip(fixtures::sensor_ticks(0, sensor_block_t::MAX_TICKS));
  EXPECT_EQ(s.y_m.size(), static_cast<std::size_t>(sensor_block_t::MAX_TICKS));
  const auto c = round_trip(fixtures::command_ticks(0, command_block_t::MAX_TICKS, 0));
  EXPECT_EQ(c.mode.size(), static_cast<std::size_t>(command_block_t::MAX_TICKS));
}

TEST(LcmTypes, TrajectoryRoundTripsEveryFieldAndPoint) {
  const auto in = fixtures::trajectory(5);  // 6 points
  const auto out = round_trip(in);
  EXPECT_EQ(out.utime, in.utime);
  EXPECT_EQ(out.version, in.version);
  EXPECT_EQ(out.shape, trajectory_t::POINTS);
  EXPECT_EQ(out.amplitude_m, in.amplitude_m);
  EXPECT_EQ(out.offset_m, in.offset_m);
  EXPECT_EQ(out.frequency_Hz, in.frequency_Hz);
  EXPECT_EQ(out.phase_rad, in.phase_rad);
  EXPECT_EQ(out.start_utime, in.start_utime);
  EXPECT_EQ(out.blend_s, in.blend_s);
  ASSERT_EQ(out.n_points, 6);
  EXPECT_EQ(out.points_t_s, in.points_t_s);
  EXPECT_EQ(out.points_y_m, in.points_y_m);
}

TEST(LcmTypes, TrajectoryWithNoPointsRoundTrips) {
  auto in = fixtures::trajectory(0);
  in.shape = trajectory_t::COSINE;
  in.n_points = 0;
  in.points_t_s.clear();
  in.points_y_m.clear();
  const auto out = round_trip(in);
  EXPECT_EQ(out.n_points, 0);
  EXPECT_TRUE(out.points_t_s.empty());
}

TEST(LcmTypes, MemParamsRoundTripsEveryField) {
  const auto in = fixtures::params(4);
  const auto out = round_trip(in);
  EXPECT_EQ(out.utime, in.utime);
  EXPECT_EQ(out.version, 5);
  EXPECT_EQ(out.publisher_id, in.publisher_id);
  EXPECT_NE(out.publisher_id, 0);
  EXPECT_EQ(out.c1, in.c1);
  EXPECT_EQ(out.c2, in.c2);
  EXPECT_EQ(out.c3, in.c3);
  EXPECT_EQ(out.residual_m, in.residual_m);
  EXPECT_EQ(out.samples_used, in.samples_used);
  EXPECT_EQ(out.window_s, in.window_s);
  EXPECT_EQ(out.valid, in.valid);
  EXPECT_EQ(out.source, "reident@lab-host-4");
}

TEST(LcmTypes, ServiceStatusRoundTripsEveryFieldAndCounter) {
  const auto in = fixtures::status(4);  // 4 counters
  const auto out = round_trip(in);
  EXPECT_EQ(out.utime, in.utime);
  EXPECT_EQ(out.process, "compensator");
  EXPECT_EQ(out.host, in.host);
  EXPECT_EQ(out.pid, in.pid);
  EXPECT_EQ(out.state, service_status_t::DEGRADED);
  EXPECT_EQ(out.detail, in.detail);
  EXPECT_EQ(out.start_utime, in.start_utime);
  ASSERT_EQ(out.n_counters, 4);
  EXPECT_EQ(out.counter_names, in.counter_names);
  EXPECT_EQ(out.counter_values, in.counter_values);
  EXPECT_EQ(out.loop_p50_us, in.loop_p50_us);
  EXPECT_EQ(out.loop_p99_us, in.loop_p99_us);
  EXPECT_EQ(out.loop_max_us, in.loop_max_us);
  EXPECT_EQ(out.latency_p50_us, in.latency_p50_us);
  EXPECT_EQ(out.latency_p99_us, in.latency_p99_us);
  EXPECT_EQ(out.latency_max_us, in.latency_max_us);
  EXPECT_EQ(out.late, in.late);
  EXPECT_EQ(out.rejected, in.rejected);
}

TEST(LcmTypes, ControlRoundTripsEveryField) {
  const auto in = fixtures::control(3);
  const auto out = round_trip(in);
  EXPECT_EQ(out.utime, in.utime);
  EXPECT_EQ(out.request_id, 103);
  EXPECT_EQ(out.command, control_t::START_EXPERIMENT);
  EXPECT_EQ(out.target, "compensator");
  EXPECT_EQ(out.mode, command_block_t::MODE_EXPERIMENT);
  EXPECT_EQ(out.kp, in.kp);
  EXPECT_EQ(out.ki, in.ki);
  EXPECT_EQ(out.kd, in.kd);
  EXPECT_EQ(out.experiment, "sine");
  EXPECT_EQ(out.experiment_amplitude_V, in.experiment_amplitude_V);
  EXPECT_EQ(out.experiment_offset_V, in.experiment_offset_V);
  EXPECT_EQ(out.experiment_frequency_Hz, in.experiment_frequency_Hz);
  EXPECT_EQ(out.experiment_duration_s, in.experiment_duration_s);
}

TEST(LcmTypes, NaNSentinelSurvivesTheWire) {
  auto in = fixtures::command_block(1);
  in.y_ref_m.assign(in.y_ref_m.size(), std::numeric_limits<double>::quiet_NaN());
  for (const double y : round_trip(in).y_ref_m) EXPECT_TRUE(std::isnan(y));
}

// Values other code depends on: common/loop/bridge_core.hpp's sample_flags and
// common/loop/trajectory.hpp's TrajectoryShape repeat them.
TEST(LcmTypes, ConstantsAreTheContractedValues) {
  EXPECT_EQ(sensor_block_t::SATURATED, 1);
  EXPECT_EQ(sensor_block_t::SAFE_STATE, 2);
  EXPECT_EQ(sensor_block_t::SIMULATED, 4);
  EXPECT_EQ(sensor_block_t::SLEW_LIMITED, 8);
  EXPECT_EQ(sensor_block_t::LATE_COMMAND, 16);
  EXPECT_EQ(sensor_block_t::SENSOR_FAULT, 32);
  EXPECT_EQ(sensor_block_t::MAX_TICKS, 1000);
  EXPECT_EQ(command_block_t::MAX_TICKS, 1000);
  EXPECT_EQ(command_block_t::MODE_OFF, 0);
  EXPECT_EQ(command_block_t::MODE_LINEAR, 1);
  EXPECT_EQ(command_block_t::MODE_MEM, 2);
  EXPECT_EQ(command_block_t::MODE_PI, 3);
  EXPECT_EQ(command_block_t::MODE_KATALENIC, 4);
  EXPECT_EQ(command_block_t::MODE_EXPERIMENT, 5);
  EXPECT_EQ(trajectory_t::HOLD, 0);
  EXPECT_EQ(trajectory_t::SINE, 1);
  EXPECT_EQ(trajectory_t::COSINE, 2);
  EXPECT_EQ(trajectory_t::TRIANGLE, 3);
  EXPECT_EQ(trajectory_t::POINTS, 4);
  EXPECT_EQ(trajectory_t::MAX_POINTS, 256);
  EXPECT_EQ(service_status_t::STARTING, 0);
  EXPECT_EQ(service_status_t::STOPPING, 4);
  EXPECT_EQ(control_t::SET_MODE, 1);
  EXPECT_EQ(control_t::SHUTDOWN, 8);
}

// The loop core keeps its own copies of these values (it has no LCM); they must agree.
static_assert(sample_flags::kSaturated == sensor_block_t::SATURATED);
static_assert(sample_flags::kSafeState == sensor_block_t::SAFE_STATE);
static_assert(sample_flags::kSimulated == sensor_block_t::SIMULATED);
static_assert(sample_flags::kSlewLimited == sensor_block_t::SLEW_LIMITED);
static_assert(sample_flags::kLateCommand == sensor_block_t::LATE_COMMAND);
static_assert(static_cast<int>(TrajectoryShape::kHold) == trajectory_t::HOLD);
static_assert(static_cast<int>(TrajectoryShape::kSine) == trajectory_t::SINE);
static_assert(static_cast<int>(TrajectoryShape::kCosine) == trajectory_t::COSINE);
static_assert(static_cast<int>(TrajectoryShape::kTriangle) == trajectory_t::TRIANGLE);
static_assert(static_cast<int>(TrajectoryShape::kPoints) == trajectory_t::POINTS);
static_assert(TrajectorySpec::kMaxPoints == static_cast<std::size_t>(trajectory_t::MAX_POINTS));

TEST(LcmTypes, BlocksHaveTheirWireSize) {
  // 8-byte fingerprint + header (n_ticks, n_axes, n_values) + per-tick arrays: what 10 kHz of
  // ticks of one axis costs on the wire.
  EXPECT_EQ(fixtures::sensor_ticks(0, 10).getEncodedSize(), 8 + 8 + 8 + 8 + 4 + 4 + 1 + 4 + 10 * (5 * 8 + 4));
  EXPECT_EQ(fixtures::command_ticks(0, 10, 0).getEncodedSize(), 8 + 3 * 8 + 4 + 1 + 4 + 10 * (2 * 8 + 4 + 1));
}

}  // namespace
}  // namespace hystloop
