// hystloop-compensator's wiring, driven through its handlers over the in-process memq provider:
// a command per sample for tick k + lead, allocation-free; the commands are a deterministic
// function of the messages; parameter sets are taken only when valid and newer; a trajectory's
// version is applied once; feedback is held while the bridge is in its safe state; control
// requests that make no sense are refused and counted.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "compensator/compensator_service.hpp"
#include "compensator/trajectory_message.hpp"
#include "lcm/connection.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

CompensatorSettings settings() {
  CompensatorSettings s = load_compensator_settings(
      Config::load_file(std::string(HYSTLOOP_SOURCE_DIR) + "/deploy/config/compensator.yaml"));
  s.trajectory.shape = TrajectoryShape::kCosine;
  s.trajectory.amplitude_m = -1.6e-6;
  s.trajectory.blend_s = 0.05;
  return s;
}

sensor_sample_t sample(std::int64_t k, double u, double y, std::int32_t flags = 0) {
  sensor_sample_t m{};
  m.seq = k;
  m.utime = 1'700'000'000'000'000 + k * 100;
  m.u_V = u;
  m.y_m = y;
  m.flags = flags;
  return m;
}

control_t request(std::int64_t id, std::int8_t command) {
  control_t c{};
  c.request_id = id;
  c.command = command;
  return c;
}

struct Harness {
  std::unique_ptr<lcm::LCM> lcm = open_lcm("memq://");
  ChannelNames channels{};
  CompensatorService service;
  explicit Harness(const CompensatorSettings& s = settings()) : service(s, *lcm, channels) {}

  // A crude plant: y follows u with the stage's mean slope; returns the commands' voltages.
  std::vector<double> run(std::int64_t from, std::int64_t ticks, std::int32_t flags = 0) {
    std::vector<double> u;
    double applied = 0.0;
    for (std::int64_t k = from; k < from + ticks; ++k) {
      service.on_sample(sample(k, applied, 6.3e-9 * applied, flags), wall_utime());
      u.push_back(service.last_command().u_V);
      applied = service.last_command().u_V;
    }
    return u;
  }
};

TEST(CompensatorService, AnswersEachSampleWithTheCommandForALaterTick) {
  Harness h;
  h.run(5000, 6000);
  const actuator_command_t& c = h.service.last_command();
  EXPECT_EQ(c.sample_seq, 10999);
  EXPECT_EQ(c.seq, 11001);  // lead_ticks = 2
  EXPECT_EQ(c.mode, actuator_command_t::MODE_MEM);
  EXPECT_TRUE(std::isfinite(c.y_ref_m));
  EXPECT_NEAR(c.u_V, c.u_ff_V + c.u_fb_V, 1e-9);
  // The cosine started 50 ms after the first sample: 0.55 s into -1.6 um cos(2 pi t).
  EXPECT_NEAR(c.y_ref_m, -1.6e-6 * std::cos(2.0 * M_PI * (0.6001 - 0.5003 - 0.05 + 0.5)), 1e-12);
  EXPECT_EQ(h.service.counters().commands_published, 6000u);
}

TEST(CompensatorService, ThePerSamplePathDoesNotAllocate) {
  Harness h;
  h.run(0, 1000);  // first sample starts the trajectory (allocates nothing either, but warms up)
  const sensor_sample_t first = sample(1000, 0.0, 0.0);
  std::vector<sensor_sample_t> samples(5000, first);
  for (std::size_t i = 0; i < samples.size(); ++i) samples[i] = sample(1000 + static_cast<std::int64_t>(i), 10.0, 6e-8);
  testing::AllocationCounter counter;
  for (const sensor_sample_t& s : samples) h.service.on_sample(s, s.utime + 20);
  EXPECT_EQ(counter.allocations(), 0u);
}

TEST(CompensatorService, CommandsAreADeterministicFunctionOfTheMessages) {
  Harness a, b;
  trajectory_t t{};
  t.version = 3;
  t.shape = trajectory_t::TRIANGLE;
  t.amplitude_m = 1e-6;
  t.frequency_Hz = 5.0;
  t.blend_s = 0.01;
  const auto ua1 = a.run(100, 500);
  const auto ub1 = b.run(100, 500);
  a.service.on_trajectory(t);
  b.service.on_trajectory(t);
  const auto ua2 = a.run(600, 3000);
  const auto ub2 = b.run(600, 3000);
  EXPECT_EQ(ua1, ub1);
  EXPECT_EQ(ua2, ub2);
  EXPECT_EQ(a.service.counters().trajectories, 2u);  // the configured one, then v3
}

TEST(CompensatorService, TakesOnlyValidNewerParameterSets) {
  Harness h;
  h.run(0, 100);
  mem_params_t p{};
  p.version = 2;
  p.c1 = 5.5e-9;
  p.c2 = 1.5e-12;
  p.c3 = 1.1;
  p.valid = false;
  h.service.on_params(p);
  EXPECT_EQ(h.service.counters().params_invalid, 1u);
  p.valid = true;
  h.service.on_params(p);
  EXPECT_EQ(h.service.compensator().counters().params_accepted, 1u);
  h.service.on_params(p);  // the same version again
  EXPECT_EQ(h.service.counters().params_stale, 1u);
  p.version = 3;
  p.c1 = -1e-9;  // outside the model's domain: refused by the compensator's own validation
  h.service.on_params(p);
  EXPECT_EQ(h.service.counters().params_refused, 1u);
  h.run(100, 12000);  // past a reversal of the 1 Hz cosine: v2 swapped in
  EXPECT_EQ(h.service.compensator().params_version(), 2);
  EXPECT_EQ(h.service.last_command().params_version, 2);
  EXPECT_EQ(h.service.compensator().mem_params().c1, 5.5e-9);
}

TEST(CompensatorService, AppliesATrajectoryVersionOnceAndRefusesABadOne) {
  Harness h;
  h.run(0, 10);
  trajectory_t t{};
  t.version = 1;
  t.shape = trajectory_t::HOLD;
  t.offset_m = 2e-7;
  h.service.on_trajectory(t);
  h.service.on_trajectory(t);
  EXPECT_EQ(h.service.counters().trajectory_repeats, 1u);
  t.version = 2;
  t.shape = trajectory_t::POINTS;  // POINTS without points
  h.service.on_trajectory(t);
  EXPECT_EQ(h.service.counters().trajectory_refused, 1u);
  h.run(10, 2000);
  EXPECT_NEAR(h.service.last_command().y_ref_m, 2e-7, 1e-12);  // held at the offset, blend done
}

TEST(CompensatorService, ATimedTrajectoryStartsAtItsLoopTime) {
  Harness h;
  h.run(0, 10);
  trajectory_t t{};
  t.version = 5;
  t.shape = trajectory_t::HOLD;
  t.offset_m = 1e-7;
  t.blend_s = 0.01;
  t.start_utime = sample(1000, 0, 0).utime;  // tick 1000's wall time: approach over ticks 900..1000
  h.service.on_trajectory(t);
  h.run(10, 880);
  EXPECT_LT(std::abs(h.service.last_command().y_ref_m), 1e-8);  // tick 891: still holding near 0
  h.run(890, 60);
  EXPECT_GT(h.service.last_command().y_ref_m, 1e-9);  // tick 951: approaching
  EXPECT_LT(h.service.last_command().y_ref_m, 1e-7);
  h.run(950, 60);
  EXPECT_NEAR(h.service.last_command().y_ref_m, 1e-7, 1e-15);  // tick 1011: there
  t.version = 6;
  t.start_utime = sample(100, 0, 0).utime;  // already past: started now, counted
  h.service.on_trajectory(t);
  EXPECT_EQ(h.service.counters().trajectory_late_start, 1u);
}

TEST(CompensatorService, HoldsFeedbackWhileTheBridgeIsSafe) {
  Harness h;
  // SAFE_STATE for 0.4 s: the bridge holds 0 V whatever we say, the stage stays at 0 while the
  // reference moves away (~1 um): integrating that error would saturate the feedback (250 V).
  for (std::int64_t k = 0; k < 4000; ++k) h.service.on_sample(sample(k, 0.0, 0.0, 2), sample(k, 0, 0).utime);
  EXPECT_EQ(h.service.counters().feedback_holds, 1u);
  EXPECT_EQ(h.service.last_command().u_fb_V, 0.0);
  h.service.on_sample(sample(4000, 0.0, 0.0), sample(4000, 0, 0).utime);  // re-armed
  const double e = h.service.last_command().y_ref_m;  // ~ the error: y = 0
  ASSERT_GT(std::abs(e), 5e-7);
  // Only this tick's proportional and integral parts, (kp + ki dt) e / gain, ~24 V; a wound-up
  // integrator would be at the 250 V limit.
  const double expected = (0.1 + 600.0 * 1e-4) * e / 6.3e-9;
  EXPECT_NEAR(h.service.last_command().u_fb_V, expected, 0.1 * std::abs(expected));
}

TEST(CompensatorService, ControlRequests) {
  Harness h;
  h.run(0, 10);
  control_t c = request(1, control_t::SET_MODE);
  c.mode = actuator_command_t::MODE_PI;
  h.service.on_control(c);
  EXPECT_EQ(h.service.compensator().mode(), FeedforwardMode::kPi);
  h.service.on_control(c);  // a repeat of request 1: acted on once
  EXPECT_EQ(h.service.counters().control_acted, 1u);
  c = request(2, control_t::SET_MODE);
  c.mode = actuator_command_t::MODE_EXPERIMENT;
  h.service.on_control(c);
  EXPECT_EQ(h.service.counters().control_refused, 1u);
  c = request(3, control_t::START_EXPERIMENT);
  c.experiment = "sine";
  c.experiment_amplitude_V = 100.0;
  c.experiment_frequency_Hz = 10.0;
  c.experiment_duration_s = 0.1;
  h.service.on_control(c);
  EXPECT_TRUE(h.service.compensator().experiment_running());
  h.run(10, 10);
  EXPECT_EQ(h.service.last_command().mode, actuator_command_t::MODE_EXPERIMENT);
  EXPECT_TRUE(std::isnan(h.service.last_command().y_ref_m));
  c = request(4, control_t::STOP_EXPERIMENT);
  h.service.on_control(c);
  h.run(20, 5);
  EXPECT_FALSE(h.service.compensator().experiment_running());
  c = request(5, control_t::ARM);
  c.target = "compensator";  // the bridge's command, addressed to us
  h.service.on_control(c);
  EXPECT_EQ(h.service.counters().control_refused, 2u);
  c = request(6, control_t::SET_GAINS);
  c.kp = 0.2;
  c.ki = 300.0;
  h.service.on_control(c);
  EXPECT_EQ(h.service.counters().control_acted, 4u);
}

TEST(CompensatorService, RestartsTheControlLawWhenTheBridgeRestarts) {
  Harness h;
  h.run(50000, 100);
  h.run(0, 100);  // seq went back by far more than a reorder: a new bridge
  EXPECT_EQ(h.service.counters().bridge_restarts, 1u);
  EXPECT_EQ(h.service.last_command().seq, 101);
  EXPECT_EQ(h.service.compensator().counters().out_of_order, 0u);
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
