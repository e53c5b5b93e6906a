// hystloop-ctl's plain parts: request validation and conversion, the health verdict, the
// watch arithmetic and its line, the series tracker.
#include <limits>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <optional>
#include <fstream>
#include <numbers>
#include <algorithm>
#include <random>
#include <vector>

#include "core/errors.hpp"
#include "ctl_ack.hpp"
#include "ctl_coupling.hpp"
#include "ctl_health.hpp"
#include "ctl_requests.hpp"
#include "ctl_series.hpp"
#include "ctl_verdict.hpp"
#include "ctl_watch.hpp"
#include "hystloop/command_block_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/message_storage.hpp"
#include "lcm/message_checks.hpp"
#include "lcm/servo_gains_status.hpp"

using namespace hystloop;
using namespace hystloop::ctl;

namespace {

template <class F>
std::string field_of(F&& f) {
  try {
    f();
  } catch (const ParameterError& e) {
    return e.field();
  }
  return "<no error>";
}

}  // namespace

TEST(CtlRequests, ModesByName) {
  EXPECT_EQ(parse_mode("mem"), command_block_t::MODE_MEM);
  EXPECT_EQ(parse_mode("katalenic"), command_block_t::MODE_KATALENIC);
  EXPECT_EQ(parse_mode("off"), command_block_t::MODE_OFF);
  try {
    parse_mode("experiment");  // has its own subcommand
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "mode");
    EXPECT_NE(std::string(e.what()).find("expected off, linear, mem, pi or katalenic"), std::string::npos);
  }
}

TEST(CtlRequests, RequestIdsArePositiveAndDiffer) {
  EXPECT_GT(new_request_id(1'700'000'000'000'000, 123), 0);
  EXPECT_NE(new_request_id(1'700'000'000'000'000, 123), new_request_id(1'700'000'000'000'001, 123));
  EXPECT_NE(new_request_id(1'700'000'000'000'000, 123), new_request_id(1'700'000'000'000'000, 124));
}

TEST(CtlRequests, GainsAndExperimentAreCheckedAndPassTheContract) {
  EXPECT_EQ(field_of([] { GainsRequest{-1, 0, 0, std::nullopt, std::nullopt}.validate(); }), "kp");
  EXPECT_EQ(field_of([] {
              GainsRequest{0, std::numeric_limits<double>::quiet_NaN(), 0, std::nullopt, std::nullopt}.validate();
            }),
            "ki");
  ExperimentRequest x;
  x.amplitude_V = 10;
  x.frequency_Hz = 0;
  x.duration_s = 1;
  EXPECT_EQ(field_of([&] { x.validate(); }), "frequency");
  x.frequency_Hz = 5;
  control_t msg = make_control(control_t::START_EXPERIMENT, "", 9, 1);
  apply(x, msg);
  EXPECT_EQ(check_message(msg), Verdict::kOk);
  EXPECT_EQ(msg.experiment, "sine");
  x.duration_s = -2;
  EXPECT_EQ(field_of([&] { x.validate(); }), "duration");
}

// experiment --kind multisine --band 5:3000 --amplitude 5 --periods 4 --realisations 3: the band
// parsed, the request on the wire in the grammar the compensator parses back (loop/experiment.hpp).
TEST(CtlRequests, AMultisineTravelsInTheExperimentsFields) {
  ExperimentRequest x;
  x.kind = "multisine";
  parse_band("5:3000", x);
  EXPECT_EQ(x.multisine.f_min_hz, 5.0);
  EXPECT_EQ(x.frequency_Hz, 3000.0);
  x.amplitude_V = 5.0;
  x.offset_V = 1.0;
  x.duration_s = 0.2;
  x.multisine.periods = 4;
  x.multisine.realisations = 3;
  control_t msg = make_control(control_t::START_EXPERIMENT, "", 9, 1);
  apply(x, msg);
  EXPECT_EQ(check_message(msg), Verdict::kOk);
  EXPECT_EQ(msg.experiment, "multisine f_min=5 periods=4 realisations=3");
  EXPECT_EQ(msg.experiment_frequency_Hz, 3000.0);
  EXPECT_EQ(msg.experiment_duration_s, 0.2);
  const ExperimentSpec back = make_experiment_spec(msg.experiment, msg.experiment_amplitude_V, msg.experiment_offset_V,
                                                   msg.experiment_frequency_Hz, msg.experiment_duration_s);
  EXPECT_TRUE(back.multisine);
  EXPECT_EQ(back.ms.realisations, 3u);
  EXPECT_EQ(back.offset_V, 1.0);
  for (const char* bad : {"3000", "5:", ":3000", "3000:5", "a:b", "0:10"}) {
    ExperimentRequest y;
    EXPECT_EQ(field_of([&] { parse_band(bad, y); }), "band") << bad;
  }
  x.multisine.periods = 2;  // the first period is the transient's: too few left
  EXPECT_EQ(field_of([&] { x.validate(); }), "periods");
  x.multisine.periods = 4;
  x.multisine.f_min_hz = 0.0;
  EXPECT_EQ(field_of([&] { x.validate(); }), "band");
  x.kind = "square";
  EXPECT_EQ(field_of([&] { x.validate(); }), "kind");
}

TEST(CtlRequests, GainsCarryANotchWithinItsBounds) {
  GainsRequest g{0.1, 600, 0, 1700.0, 4.0};
  control_t msg = make_control(control_t::SET_GAINS, "bridge", 9, 1);
  apply(g, msg);
  EXPECT_EQ(msg.notch_hz, 1700.0);
  EXPECT_EQ(msg.notch_q, 4.0);
  EXPECT_EQ(check_message(msg), Verdict::kOk);
  apply(GainsRequest{0.1, 600, 0, 0.0, std::nullopt}, msg);  // --notch-hz 0 removes it
  EXPECT_EQ(msg.notch_hz, 0.0);
  EXPECT_TRUE(std::isnan(msg.notch_q));
  EXPECT_NO_THROW((GainsRequest{0, 0, 0, 4500.0, 0.1}.validate()));
  EXPECT_NO_THROW((GainsRequest{0, 0, 0, 1e-3, 50.0}.validate()));
  EXPECT_NO_THROW((GainsRequest{0, 0, 0, 1700.0, std::nullopt}.validate()));  // the Q in force stays
  EXPECT_EQ(field_of([] { GainsRequest{0, 0, 0, 4500.1, 2.0}.validate(); }), "notch-hz");
  EXPECT_EQ(field_of([] { GainsRequest{0, 0, 0, -1.0, 2.0}.validate(); }), "notch-hz");
  EXPECT_EQ(field_of([] {
              GainsRequest{0, 0, 0, std::numeric_limits<double>::quiet_NaN(), 2.0}.validate();
            }),
            "notch-hz");
  EXPECT_EQ(field_of([] { GainsRequest{0, 0, 0, 1700.0, 0.09}.validate(); }), "notch-q");
  EXPECT_EQ(field_of([] { GainsRequest{0, 0, 0, 1700.0, 50.5}.validate(); }), "notch-q");
  EXPECT_EQ(field_of([] { GainsRequest{0, 0, 0, 0.0, 3.0}.validate(); }), "notch-q");  // a Q without a notch
}

TEST(CtlRequests, AGainNotGivenIsSentAsNaNSoTheBridgeKeepsItsOwn) {
  GainsRequest g;
  EXPECT_TRUE(g.empty());  // a question, not a request
  g.kp = 0.2;
  EXPECT_FALSE(g.empty());
  control_t msg = make_control(control_t::SET_GAINS, "bridge", 9, 1);
  apply(g, msg);
  EXPECT_EQ(msg.kp, 0.2);
  EXPECT_TRUE(std::isnan(msg.ki));
  EXPECT_TRUE(std::isnan(msg.kd));
  EXPECT_TRUE(std::isnan(msg.notch_hz));
  EXPECT_TRUE(std::isnan(msg.notch_q));
  EXPECT_TRUE(std::isnan(msg.notch2_hz));
  EXPECT_TRUE(std::isnan(msg.notch2_q));
  EXPECT_EQ(check_message(msg), Verdict::kOk);
  // The second notch travels in its own fields, checked by its own names.
  g.notch2_hz = 2400.0;
  g.notch2_q = 3.0;
  apply(g, msg);
  EXPECT_EQ(msg.notch2_hz, 2400.0);
  EXPECT_EQ(msg.notch2_q, 3.0);
  EXPECT_TRUE(std::isnan(msg.notch_hz));
  EXPECT_EQ(field_of([] {
              GainsRequest r;
              r.notch2_hz = 4600.0;
              r.validate();
            }),
            "notch2-hz");
  g.notch2_hz.reset();
  g.notch2_q.reset();
  g.ki = 2e4;  // past ki dt <= 1 at 10 kHz, given alone
  EXPECT_EQ(field_of([&] { g.validate(); }), "ki");
}

TEST(CtlRequests, LearningByName) {
  EXPECT_EQ(parse_learning("on"), control_t::LEARNING_ON);
  EXPECT_EQ(parse_learning("off"), control_t::LEARNING_OFF);
  EXPECT_EQ(parse_learning("reset"), control_t::LEARNING_RESET);
  try {
    parse_learning("yes");
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "learning");
    EXPECT_NE(std::string(e.what()).find("on|off|reset"), std::string::npos) << e.what();
  }
}

TEST(CtlRequests, TriangleCornerAndTheInfeasiblePolicy) {
  TrajectoryRequest r;
  r.shape = "triangle";
  r.amplitude_m = 1e-6;
  r.frequency_Hz = 10.0;
  trajectory_t t = make_trajectory(r, 1, 1);
  EXPECT_EQ(t.corner_s, 0.0);  // the compensator's choice
  EXPECT_EQ(t.if_infeasible, trajectory_t::REFUSE);
  r.corner_s = 0.004;
  r.shape_to_feasible = true;
  t = make_trajectory(r, 2, 2);
  EXPECT_EQ(t.corner_s, 0.004);
  EXPECT_EQ(t.if_infeasible, trajectory_t::SHAPE);
  r.corner_s = 0.05;  // half the period
  EXPECT_EQ(field_of([&] { r.validate(); }), "corner");
  r.corner_s = -1e-3;
  EXPECT_EQ(field_of([&] { r.validate(); }), "corner");
  r.corner_s = 0.01;
  r.shape = "sine";
  EXPECT_EQ(field_of([&] { r.validate(); }), "corner");  // only for a triangle
  r.corner_s = 0.0;
  EXPECT_EQ(make_trajectory(r, 3, 3).if_infeasible, trajectory_t::SHAPE);  // any shape may be shaped
}

TEST(CtlRequests, MemPaperTrajectory) {
  const trajectory_t t = make_trajectory(mem_paper_trajectory(0.5), 3, 4);
  EXPECT_EQ(t.shape, trajectory_t::COSINE);
  EXPECT_DOUBLE_EQ(t.amplitude_m, -1.6e-6);
  EXPECT_DOUBLE_EQ(t.frequency_Hz, 1.0);
  EXPECT_DOUBLE_EQ(t.offset_m, 0.0);
  EXPECT_DOUBLE_EQ(t.blend_s, 0.5);
  EXPECT_EQ(t.version, 3);
  EXPECT_EQ(t.start_utime, 0);
}

TEST(CtlRequests, TrajectoryValidationNamesTheOption) {
  TrajectoryRequest r;
  r.shape = "square";
  EXPECT_EQ(field_of([&] { r.validate(); }), "shape");
  r.shape = "sine";
  r.frequency_Hz = 0;
  EXPECT_EQ(field_of([&] { r.validate(); }), "frequency");
  r.frequency_Hz = 1;
  r.blend_s = -1;
  EXPECT_EQ(field_of([&] { r.validate(); }), "blend");
  r.blend_s = 0;
  r.amplitude_m = 2.0;  // 2 m: surely micrometres were meant
  EXPECT_EQ(field_of([&] { r.validate(); }), "amplitude");
  r.amplitude_m = 1e-6;
  r.shape = "hold";
  r.frequency_Hz = 0;  // ignored for hold
  EXPECT_NO_THROW(r.validate());
  r.shape = "points";
  EXPECT_EQ(field_of([&] { r.validate(); }), "points-csv");
}

TEST(CtlRequests, PointsCsv) {
  const auto file = std::filesystem::temp_directory_path() / ("ctl_points_" + std::to_string(::getpid()) + ".csv");
  {
    std::ofstream out(file);
    out << "t_s,y_m\n# a comment\n0,0\n0.5, 1e-6\n1.0;2e-6\n";
  }
  TrajectoryRequest r;
  r.shape = "points";
  read_points_csv(file, r);
  ASSERT_EQ(r.points_t_s.size(), 3u);
  EXPECT_DOUBLE_EQ(r.points_y_m[2], 2e-6);
  const trajectory_t t = make_trajectory(r, 1, 1);
  EXPECT_EQ(t.n_points, 3);
  EXPECT_EQ(t.shape, trajectory_t::POINTS);
  {
    std::ofstream out(file);
    out << "0,0\n1,1e-6\n0.5,0\n";
  }
  read_points_csv(file, r);
  EXPECT_EQ(field_of([&] { r.validate(); }), "points-csv");
  {
    std::ofstream out(file);
    out << "0,0\n1,abc\n";
  }
  try {
    read_points_csv(file, r);
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
  }
  std::filesystem::remove(file);
}

TEST(CtlRequests, ParamsValidation) {
  ParamsRequest p{1e-7, 1e-9, 0.5, 0, 1};
  const mem_params_t msg = make_params(p, 5);
  EXPECT_TRUE(msg.valid);
  EXPECT_NE(msg.publisher_id, 0);  // the run's own: a new publisher, never stale at the compensator
  EXPECT_EQ(make_params(p, 6).publisher_id, msg.publisher_id);
  EXPECT_EQ(msg.source, "hystloop-ctl");
  EXPECT_EQ(check_message(msg), Verdict::kOk);
  p.c1 = -1;
  EXPECT_EQ(field_of([&] { p.validate(); }), "c1");
  try {
    p.validate();
  } catch (const ParameterError& e) {
    EXPECT_STREQ(e.what(), "c1: must be > 0 (got -1)");
  }
  p.c1 = 1e-7;
  p.c2 = -1e-9;
  EXPECT_EQ(field_of([&] { p.validate(); }), "c2");
  p.c2 = 0;
  p.c3 = 0;
  EXPECT_EQ(field_of([&] { p.validate(); }), "c3");
  p.c3 = 51;
  EXPECT_EQ(field_of([&] { p.validate(); }), "c3");
  p.c3 = 1;
  p.version = 0;
  EXPECT_EQ(field_of([&] { p.validate(); }), "version");
}

TEST(CtlRequests, TrajectoriesAndParametersNameTheirAxis) {
  TrajectoryRequest t;
  t.shape = "sine";
  t.amplitude_m = 1e-7;
  EXPECT_EQ(make_trajectory(t, 1, 1).axis, 0);  // x unless told
  t.axis = 1;
  EXPECT_EQ(make_trajectory(t, 2, 2).axis, 1);
  ParamsRequest p{1e-7, 1e-9, 0.5, 0, 1};
  p.axis = 2;
  EXPECT_EQ(make_params(p, 5).axis, 2);
}

TEST(CtlRequests, ScansAreCheckedAndPassTheContract) {
  ScanRequest r;
  r.path = "raster";
  r.lines = 32;
  r.line_rate_Hz = 25.0;
  r.centre_m = {1e-7, -1e-7};
  const scan_t raster = make_scan(r, 7, 8);
  EXPECT_EQ(raster.path, scan_t::RASTER);
  EXPECT_EQ(raster.version, 7);
  EXPECT_EQ(raster.lines, 32);
  EXPECT_EQ(raster.fast_axis, 0);
  EXPECT_EQ(raster.slow_axis, 1);
  EXPECT_EQ(raster.centre_m[1], -1e-7);
  EXPECT_EQ(raster.centre_m[2], 0.0);
  EXPECT_TRUE(raster.decouple);
  EXPECT_EQ(check_message(raster), Verdict::kOk);

  ScanRequest l;
  l.path = "lissajous";
  l.amplitude_m = {5e-7, 5e-7};
  l.frequency_Hz = {50, 48};
  l.decouple = false;
  const scan_t fig = make_scan(l, 9, 9);
  EXPECT_EQ(fig.path, scan_t::LISSAJOUS);
  EXPECT_EQ(fig.frequency_Hz[1], 48.0);
  EXPECT_FALSE(fig.decouple);

  ScanRequest bad = r;
  bad.slow_axis = 0;
  EXPECT_EQ(field_of([&] { bad.validate(); }), "slow-axis");
  bad = r;
  bad.lines = 1;
  EXPECT_EQ(field_of([&] { bad.validate(); }), "lines");
  bad = r;
  bad.slow = "jump";
  EXPECT_EQ(field_of([&] { bad.validate(); }), "slow");
  bad = r;
  bad.path = "spiral";
  EXPECT_EQ(field_of([&] { bad.validate(); }), "path");
  bad = l;
  bad.frequency_Hz = {50};
  EXPECT_EQ(field_of([&] { bad.validate(); }), "frequency");
  bad = l;
  bad.amplitude_m = {1e-7, 1e-7, 1e-7, 1e-7};
  EXPECT_EQ(field_of([&] { bad.validate(); }), "amplitude");
}

TEST(CtlCoupling, RecordsOfEachAxisGiveTheCouplingAndTheCompensatorsKeys) {
  // x moves y by 3 %, y moves x by nothing; each record: the moved axis a 1 um triangle.
  std::vector<CouplingRecord> records(2);
  for (int a = 0; a < 2; ++a) {
    records[static_cast<std::size_t>(a)].axis = a;
    for (int k = 0; k < 2000; ++k) {
      const double own = 1e-6 * std::abs((k % 400) - 200) / 200.0;
      const double other = a == 0 ? 0.03 * own + 2e-9 : 5e-9;
      records[static_cast<std::size_t>(a)].y_m[static_cast<std::size_t>(a)].push_back(own);
      records[static_cast<std::size_t>(a)].y_m[static_cast<std::size_t>(1 - a)].push_back(other);
    }
  }
  const CouplingFitResult fit = fit_records(records, 2);
  ASSERT_TRUE(fit.ok()) << fit.reason;
  EXPECT_NEAR(fit.coupling.matrix()(1, 0), 0.03, 1e-12);
  EXPECT_NEAR(fit.coupling.matrix()(0, 1), 0.0, 1e-12);
  const std::string yaml = decoupling_yaml(fit, 2, "a test");
  EXPECT_NE(yaml.find("decoupling:\n  x_to_y: 0.03"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("  y_to_x: "), std::string::npos) << yaml;
  EXPECT_EQ(yaml.find('z'), std::string::npos) << "an XY stage has no z keys: " << yaml;
  EXPECT_NE(describe_fit(fit, 2).find("x -> y: +0.03000"), std::string::npos) << describe_fit(fit, 2);

  records.pop_back();  // y never excited: its column unknown, refused
  EXPECT_FALSE(fit_records(records, 2).ok());

  CouplingRunOptions o;
  o.duration_s = 0.1;  // half a period at 5 Hz
  EXPECT_EQ(field_of([&] { o.validate(); }), "duration");
}

// A unipolar stage (-20 .. +150 V) runs each axis's sine about an offset inside its range: the
// request carries it, and the message the compensator gets too.
TEST(CtlCoupling, EachAxisSineRunsAboutTheOffsetGiven) {
  CouplingRunOptions o;
  o.amplitude_V = 60.0;
  o.offset_V = 65.0;
  ASSERT_NO_THROW(o.validate());
  const ExperimentRequest e = coupling_experiment(o);
  EXPECT_EQ(e.offset_V, 65.0);
  EXPECT_EQ(e.amplitude_V, 60.0);
  EXPECT_EQ(e.frequency_Hz, o.frequency_Hz);
  EXPECT_EQ(e.duration_s, o.duration_s);
  control_t msg = make_control(control_t::START_EXPERIMENT, "compensator", 1, 1);
  apply(e, msg);
  EXPECT_EQ(msg.experiment_offset_V, 65.0);
  o.offset_V = std::nan("");
  EXPECT_EQ(field_of([&] { o.validate(); }), "offset");
}

namespace {
service_status_t report(const std::string& process, std::int8_t state, const std::string& detail = "") {
  service_status_t s{};
  s.process = process;
  s.host = "h";
  s.pid = 1;
  s.state = state;
  s.detail = detail;
  s.loop_p50_us = 1.5;
  s.loop_p99_us = 3.0;
  s.loop_max_us = 250.0;
  s.latency_p50_us = s.latency_p99_us = s.latency_max_us = std::numeric_limits<double>::quiet_NaN();
  return s;
}
}  // namespace

TEST(CtlHealth, VerdictNamesWhoIsMissingOrUnhealthy) {
  StatusBoard board;
  auto v = check_health(board, {"bridge", "compensator"}, {});
  EXPECT_FALSE(v.healthy);
  ASSERT_EQ(v.problems.size(), 2u);
  EXPECT_EQ(v.problems[0], "bridge: no status received");
  board.update(report("bridge", service_status_t::SAFE, "not armed"));
  board.update(report("compensator", service_status_t::HEALTHY));
  v = check_health(board, {"bridge", "compensator"}, {});
  ASSERT_EQ(v.problems.size(), 1u);
  EXPECT_EQ(v.problems[0], "bridge: SAFE (not armed)");
  EXPECT_TRUE(check_health(board, {"bridge", "compensator"}, {"bridge"}).healthy);
  board.update(report("compensator", service_status_t::DEGRADED, "late commands"));  // the latest report counts
  EXPECT_FALSE(check_health(board, {"bridge", "compensator"}, {"bridge"}).healthy);
}

TEST(CtlHealth, StatusLine) {
  StatusBoard board;
  auto s = report("bridge", service_status_t::DEGRADED, "late commands");
  s.late = 12;
  s.counter_names = {"ticks"};
  s.counter_values = {100};
  s.n_counters = 1;
  board.update(s);
  const std::string line = format_status(board.processes().at("bridge"), true);
  EXPECT_NE(line.find("DEGRADED"), std::string::npos) << line;
  EXPECT_NE(line.find("late 12"), std::string::npos) << line;
  EXPECT_NE(line.find("loop p50/p99/max 1.5/3.0/250 us"), std::string::npos) << line;
  EXPECT_NE(line.find("latency --"), std::string::npos) << line;
  EXPECT_NE(line.find("[late commands]"), std::string::npos) << line;
  EXPECT_NE(line.find("ticks = 100"), std::string::npos) << line;
}

// The error of a tick is y_ref - y as the bridge recorded both; ticks without a reference have
// none; the buffer depth counts only for blocks with no tick in the safe state.
TEST(CtlWatch, SensorBlocksGiveTheExactRmsAndTheLowestArmedBufferDepth) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 25e-9);
  constexpr std::int64_t kBlocks = 1000, kBlockTicks = 10;
  auto ref = [](std::int64_t k) { return 1e-6 * std::sin(0.01 * static_cast<double>(k)); };
  sensor_block_t b{};
  reserve_storage(b);
  WatchSecond second;
  double sum = 0.0, max_abs = 0.0;
  std::uint64_t tracking = 0;
  for (std::int64_t n = 0; n < kBlocks; ++n) {
    begin_block(b, n * kBlockTicks, 1'000'000 + n * 1000, 1e-4);
    for (std::int64_t k = n * kBlockTicks; k < (n + 1) * kBlockTicks; ++k) {
      const double e = noise(rng);
      const bool has_ref = k % 7 != 0;
      if (has_ref) sum += e * e, max_abs = std::max(max_abs, std::abs(e)), ++tracking;
      SensorTick t{};
      t.y_ref_m = has_ref ? ref(k) : std::nan("");
      t.y_m = ref(k) - e;  // e = y_ref - y
      t.flags = n == 3 && k % 10 == 9 ? sensor_block_t::SAFE_STATE : 0;
      append_tick(b, t);
    }
    b.buffer_depth_ticks = n == 3 ? 0 : static_cast<std::int32_t>(100 + n % 50);
    second.add_sensor_block(b);
  }
  EXPECT_EQ(second.samples, static_cast<std::uint64_t>(kBlocks * kBlockTicks));
  ASSERT_EQ(second.error.count, tracking);
  EXPECT_NEAR(*second.error.rms_m(), std::sqrt(sum / static_cast<double>(tracking)), 1e-15);
  EXPECT_NEAR(second.error.max_abs_m, max_abs, 1e-18);
  EXPECT_EQ(*second.buffer_min_ticks, 100);  // block 3's 0 was in the safe state
  EXPECT_FALSE(WatchSecond{}.error.rms_m());
  EXPECT_FALSE(WatchSecond{}.buffer_min_ticks);
}

// The true error pairs each truth block with the sensor block of its seq whichever comes first;
// a block whose partner was lost adds nothing, and ticks without a reference have no error.
TEST(CtlWatch, TruthBlocksPairWithTheirSensorBlocksInEitherOrder) {
  constexpr std::int64_t kBlockTicks = 4;
  auto sensor = [](std::int64_t seq) {
    sensor_block_t b{};
    reserve_storage(b);
    begin_block(b, seq, 1'000'000 + seq * 100, 1e-4);
    for (std::int64_t k = 0; k < kBlockTicks; ++k) {
      SensorTick t{};
      t.y_ref_m = k == 0 ? std::nan("") : 1e-6;
      t.y_m = 1e-6 - 2e-9;  // measured error 2 nm
      append_tick(b, t);
    }
    return b;
  };
  auto truth = [](std::int64_t seq, double error_m) {
    sim_truth_t t{};
    t.seq = seq;
    t.n_ticks = kBlockTicks;
    t.y_true_m.assign(kBlockTicks, 1e-6 - error_m);
    return t;
  };
  TruthPairing pairing;
  WatchSecond second;
  pairing.add_sensor_block(sensor(0), second);
  pairing.add_truth_block(truth(0, 1e-9), second);  // after its sensor block
  pairing.add_truth_block(truth(4, 3e-9), second);  // before it
  EXPECT_EQ(second.true_error.count, 3u);
  pairing.add_sensor_block(sensor(4), second);
  pairing.add_sensor_block(sensor(8), second);       // its truth was lost
  pairing.add_truth_block(truth(12, 1e-9), second);  // its sensor block was lost
  ASSERT_EQ(second.true_error.count, 6u);
  EXPECT_NEAR(*second.true_error.rms_m(), std::sqrt((3 * 1e-18 + 3 * 9e-18) / 6), 1e-18);
  EXPECT_NEAR(second.true_error.max_abs_m, 3e-9, 1e-21);
  sim_truth_t short_block = truth(16, 1e-9);
  short_block.y_true_m.pop_back();
  short_block.n_ticks = kBlockTicks - 1;
  pairing.add_sensor_block(sensor(16), second);
  pairing.add_truth_block(short_block, second);  // not the same ticks: not paired
  EXPECT_EQ(second.true_error.count, 6u);
  // Far more unpaired blocks than it keeps: the oldest go, the newest still pair.
  for (std::int64_t n = 0; n < 1000; ++n) pairing.add_sensor_block(sensor(100 + n * kBlockTicks), second);
  pairing.add_truth_block(truth(100 + 999 * kBlockTicks, 1e-9), second);
  pairing.add_truth_block(truth(100, 1e-9), second);
  EXPECT_EQ(second.true_error.count, 9u);
  EXPECT_FALSE(WatchSecond{}.true_error.rms_m());
}

TEST(CtlWatch, AStageOfSeveralAxesIsWatchedOneAxisAtATime) {
  sensor_block_t b{};
  reserve_storage(b);
  begin_block(b, 100, 1, 1e-4, 2);
  for (int k = 0; k < 10; ++k) {
    // x off by 1 nm, y by 3 nm, at every tick
    const std::array<SensorTick, 2> t{SensorTick{1, 100 + k, 0.0, 0.0, 0.0, 1e-6, 1e-6 - 1e-9, 0},
                                      SensorTick{1, 100 + k, 0.0, 0.0, 0.0, 2e-6, 2e-6 - 3e-9, 0}};
    ASSERT_TRUE(append_tick(b, t));
  }
  WatchSecond x, y, z;
  x.add_sensor_block(b, 0);
  y.add_sensor_block(b, 1);
  z.add_sensor_block(b, 2);  // the block has no z: nothing
  EXPECT_NEAR(*x.error.rms_m(), 1e-9, 1e-18);
  EXPECT_NEAR(*y.error.rms_m(), 3e-9, 1e-18);
  EXPECT_EQ(z.samples, 0u);

  sim_truth_t truth{};
  begin_block(truth, 100, 1, 2);
  for (int k = 0; k < 10; ++k) {
    const std::array<double, 2> v{1e-6 - 2e-9, 2e-6 - 5e-9};  // true errors 2 nm and 5 nm
    ASSERT_TRUE(append_tick(truth, v));
  }
  TruthPairing pairs_y(1);
  WatchSecond second;
  pairs_y.add_sensor_block(b, second);
  pairs_y.add_truth_block(truth, second);
  EXPECT_NEAR(*second.true_error.rms_m(), 5e-9, 1e-18);
}

TEST(CtlWatch, LineIsTidy) {
  WatchLine l;
  l.elapsed_s = 12;
  l.second.samples = 10000;
  l.second.error.add(27.9e-9);
  l.second.error.add(-27.9e-9);
  l.params_in_use = 3;
  l.params_latest = 4;
  l.late_total = 5;
  l.late_delta = 1;
  l.second.buffer_min_ticks = 212;
  l.bridge_state = "HEALTHY";
  l.clamped_per_s = 14;
  EXPECT_EQ(format_watch_line(l),
            "   12 s  rms    27.9 nm  max    27.9 nm  ticks      2/10000  params v3 (v4 published)  late 5 (+1)  "
            "clamped 14/s  buf min 212  bridge HEALTHY");
  WatchLine with_truth = l;
  with_truth.second.true_error.add(0.55e-9);
  with_truth.second.true_error.add(-3.1e-9);
  EXPECT_NE(format_watch_line(with_truth).find("max    27.9 nm  true 2.23 nm max 3.1 nm  ticks      2/10000"),
            std::string::npos)
      << format_watch_line(with_truth);
  l.learning_rms_nm = 9;
  l.learning_periods = 31;
  EXPECT_EQ(format_watch_line(l),
            "   12 s  rms    27.9 nm  max    27.9 nm  ticks      2/10000  params v3 (v4 published)  late 5 (+1)  "
            "clamped 14/s  buf min 212  bridge HEALTHY  learned 9.0 nm (31 periods)");
  l.trajectories_refused = 0;
  l.trajectories_shaped = 0;
  EXPECT_EQ(format_watch_line(l).find("trajectories"), std::string::npos);  // none: not said
  l.trajectories_refused = 1;
  l.trajectories_shaped = 2;
  EXPECT_NE(format_watch_line(l).find("  learned 9.0 nm (31 periods)  trajectories refused 1, shaped 2"),
            std::string::npos)
      << format_watch_line(l);
  service_status_t comp{};
  comp.counter_names = {"learning_rms_pm", "learning_periods"};
  comp.counter_values = {12345, 4};
  EXPECT_EQ(learning_rms_nm(comp), std::optional<double>(12.345));
  comp.counter_names[0] = "learning_rms_nm";
  EXPECT_EQ(learning_rms_nm(comp), std::optional<double>(12345.0));
  EXPECT_EQ(learning_rms_nm(service_status_t{}), std::nullopt);
  // Another axis's behind its name; x's is not y's.
  comp.counter_names = {"learning_rms_pm", "y_learning_rms_pm"};
  comp.counter_values = {12345, 678};
  EXPECT_EQ(learning_rms_nm(comp, 1), std::optional<double>(0.678));
  EXPECT_EQ(learning_rms_nm(comp, 2), std::nullopt);
  EXPECT_EQ(axis_counter("learning_periods", 2), "z_learning_periods");
  EXPECT_EQ(format_watch_line(WatchLine{}),
            "    0 s  rms      -- nm  max      -- nm  ticks      0/0  params --  late --  clamped --  buf min --  "
            "bridge --");
}

namespace {
service_status_t compensator_report(std::int64_t accepted, std::int64_t refused, std::int64_t shaped,
                                    const std::string& detail) {
  service_status_t s{};
  s.process = "compensator";
  s.detail = detail;
  s.counter_names = {"samples", "trajectory_version", "trajectory_refused_version", "trajectory_shaped_version"};
  s.counter_values = {100, accepted, refused, shaped};
  s.n_counters = 4;
  return s;
}
service_status_t answering(const std::string& process, std::int64_t acted, std::int64_t refused, std::int64_t armed,
                           const std::string& detail = {}) {
  service_status_t s{};
  s.process = process;
  s.state = service_status_t::HEALTHY;
  s.detail = detail;
  s.counter_names = {"control_acted_request", "control_refused_request", "armed"};
  s.counter_values = {acted, refused, armed};
  s.n_counters = 3;
  return s;
}

TEST(CtlAck, AReportAnswersARequestByItsIdAndTheStateItAskedFor) {
  const StateCheck armed = counter_is("armed", 1);
  EXPECT_EQ(read_ack(answering("bridge", 5, 0, 0), 6, armed).outcome, AckOutcome::kPending);
  EXPECT_EQ(read_ack(answering("bridge", 6, 0, 0), 6, armed).outcome, AckOutcome::kActed);  // not armed yet
  EXPECT_EQ(read_ack(answering("bridge", 6, 0, 1), 6, armed).outcome, AckOutcome::kConfirmed);
  EXPECT_EQ(read_ack(answering("bridge", 6, 0, 0), 6).outcome, AckOutcome::kConfirmed);  // no state to show
  const AckReading refused = read_ack(answering("bridge", 5, 6, 0, "u 0 V; request 6 refused: stopping"), 6, armed);
  EXPECT_EQ(refused.outcome, AckOutcome::kRefused);
  EXPECT_EQ(refused.detail, "stopping");
  EXPECT_EQ(read_ack(answering("bridge", 9, 0, 1), 6, armed).outcome, AckOutcome::kSkipped);
  service_status_t old_build{};
  old_build.process = "bridge";
  EXPECT_FALSE(read_ack(old_build, 6).acknowledges);
}

TEST(CtlAck, ATrackerWaitsForEveryExpectedProcessOrEveryOneHeard) {
  AckTracker for_bridge(6, {"bridge"}, counter_is("armed", 1));
  for_bridge.update(answering("compensator", 6, 0, 1));  // not the one asked
  EXPECT_FALSE(for_bridge.finished(true));
  for_bridge.update(answering("bridge", 6, 0, 0));
  EXPECT_FALSE(for_bridge.finished(true));  // took it, not armed yet
  for_bridge.update(answering("bridge", 6, 0, 1));
  EXPECT_TRUE(for_bridge.all_confirmed(true));
  for_bridge.update(answering("bridge", 7, 0, 0));  // a later request disarmed: the answer stays
  EXPECT_TRUE(for_bridge.all_confirmed(true));

  AckTracker all(6, {});
  EXPECT_FALSE(all.finished(true));  // nobody heard
  all.update(answering("bridge", 6, 0, 0));
  EXPECT_FALSE(all.finished(false));  // still gathering who runs
  EXPECT_TRUE(all.finished(true));
  all.update(answering("logger", 0, 0, 0));
  EXPECT_FALSE(all.all_confirmed(true));
  const std::vector<std::string> lines = describe_answers(all, true);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0], "'bridge' confirmed");
  EXPECT_NE(lines[1].find("'logger' did not confirm"), std::string::npos) << lines[1];
  all.update(answering("logger", 0, 6, 0, "request 6 refused: whole recording"));
  EXPECT_TRUE(all.finished(true));
  EXPECT_EQ(describe_answers(all, true)[1], "'logger' refused it: whole recording");

  AckTracker missing(6, {"bridge"});
  EXPECT_EQ(describe_answers(missing, true)[0], "'bridge' sent no status report (is it running, under this name?)");
}

TEST(CtlAck, ServoGainsTravelAsCountersAndComeBack) {
  const ServoGainsFigures g{0.1, 600.0, 2.5e-5, 1720.0, 3.5, 2400.0, 3.0};
  service_status_t s{};
  for (const ServoGainCounter& c : kServoGainCounters) {
    s.counter_names.emplace_back(c.name);
    s.counter_values.push_back(static_cast<std::int64_t>(servo_gain_counter(c, g)));
  }
  const auto back = servo_gains_from_counters([&](std::string_view name) { return find_counter(s, name); });
  ASSERT_TRUE(back.has_value());
  EXPECT_DOUBLE_EQ(back->kp, 0.1);
  EXPECT_DOUBLE_EQ(back->ki_per_s, 600.0);
  EXPECT_DOUBLE_EQ(back->kd_s, 2.5e-5);
  EXPECT_DOUBLE_EQ(back->notch_hz, 1720.0);
  EXPECT_DOUBLE_EQ(back->notch_q, 3.5);
  EXPECT_DOUBLE_EQ(back->notch2_hz, 2400.0);
  EXPECT_DOUBLE_EQ(back->notch2_q, 3.0);
  // A bridge that reports no second notch has none; one without a gain it must report, no gains.
  s.counter_names.resize(5);
  s.counter_values.resize(5);
  const auto one_notch = servo_gains_from_counters([&](std::string_view name) { return find_counter(s, name); });
  ASSERT_TRUE(one_notch.has_value());
  EXPECT_EQ(one_notch->notch2_hz, 0.0);
  s.counter_names.pop_back();
  s.counter_values.pop_back();
  EXPECT_FALSE(servo_gains_from_counters([&](std::string_view name) { return find_counter(s, name); }).has_value());
}

}  // namespace

TEST(CtlVerdict, CountersSayWhatBecameOfTheVersion) {
  EXPECT_EQ(find_counter(compensator_report(7, 0, 0, ""), "trajectory_version"), std::optional<std::int64_t>(7));
  EXPECT_EQ(find_counter(compensator_report(7, 0, 0, ""), "learning_periods"), std::nullopt);

  TrajectoryVerdict v = trajectory_verdict(compensator_report(41, 0, 0, ""), 42);
  EXPECT_EQ(v.outcome, TrajectoryOutcome::kPending);  // still the previous one
  EXPECT_TRUE(v.has_counters);
  v = trajectory_verdict(compensator_report(42, 0, 0, ""), 42);
  EXPECT_EQ(v.outcome, TrajectoryOutcome::kAccepted);
  EXPECT_EQ(v.detail, "");
  v = trajectory_verdict(compensator_report(42, 0, 0, "trajectory 42 taken: corner 97 us (the shortest)"), 42);
  EXPECT_EQ(v.outcome, TrajectoryOutcome::kAccepted);
  EXPECT_EQ(v.detail, "corner 97 us (the shortest)");
  EXPECT_EQ(trajectory_verdict(compensator_report(42, 0, 0, "late commands"), 42).detail, "");  // not about it
  v = trajectory_verdict(compensator_report(42, 0, 42, "trajectory 42 shaped: amplitude 1 um -> 0.51 um (slew)"), 42);
  EXPECT_EQ(v.outcome, TrajectoryOutcome::kShaped);
  EXPECT_EQ(v.detail, "amplitude 1 um -> 0.51 um (slew)");
  v = trajectory_verdict(compensator_report(41, 42, 0, "late commands; trajectory 42 refused: slew 9.8e4 V/s > 5e4"),
                         42);
  EXPECT_EQ(v.outcome, TrajectoryOutcome::kRefused);
  EXPECT_EQ(v.detail, "slew 9.8e4 V/s > 5e4");
  v = trajectory_verdict(compensator_report(41, 42, 0, "something else"), 42);  // no prefix: the whole detail
  EXPECT_EQ(v.detail, "something else");
  // An older shaped version does not make this one shaped.
  EXPECT_EQ(trajectory_verdict(compensator_report(42, 0, 40, ""), 42).outcome, TrajectoryOutcome::kAccepted);
  v = trajectory_verdict(compensator_report(43, 0, 0, ""), 42);
  EXPECT_EQ(v.outcome, TrajectoryOutcome::kSuperseded);
  EXPECT_EQ(v.later_version, 43);
  EXPECT_EQ(trajectory_verdict(compensator_report(41, 44, 0, ""), 42).outcome, TrajectoryOutcome::kSuperseded);
  // A compensator without the counters never answers.
  service_status_t old{};
  old.process = "compensator";
  v = trajectory_verdict(old, 42);
  EXPECT_EQ(v.outcome, TrajectoryOutcome::kPending);
  EXPECT_FALSE(v.has_counters);
  EXPECT_EQ(verdict_reason("trajectory 5 refused: range", 6, "refused"), "trajectory 5 refused: range");
}

// Banning's series as requests: per planned experiment a settling sine then the measured one,
// each a whole number of periods, together the plan's input sample for sample.
TEST(CtlSeries, BanningSeriesIsThePlanAsSettleAndMeasureRequests) {
  BanningPlanOptions plan;
  const auto experiments = plan_banning_experiments(plan);
  const auto steps = banning_series(plan);
  ASSERT_EQ(steps.size(), 2 * experiments.size());
  double total = 0.0;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const auto& r = steps[i].request;
    const auto& e = experiments[steps[i].experiment];
    EXPECT_EQ(steps[i].experiment, i / 2);
    EXPECT_EQ(r.kind, i % 2 == 0 ? "settle" : "sine");
    EXPECT_EQ(r.offset_V, e.offset_V);
    EXPECT_EQ(r.amplitude_V, e.amplitude_V);
    const double periods = r.duration_s * r.frequency_Hz;
    EXPECT_NEAR(periods, std::round(periods), 1e-9) << i;
    total += r.duration_s;
    // The request reproduces the plan's samples: the settling part, then the measured part.
    const double fs = e.sample_rate_Hz;
    const std::size_t begin = i % 2 == 0 ? 0 : e.measure_begin;
    const std::size_t end = i % 2 == 0 ? e.measure_begin : e.u.size();
    EXPECT_EQ(static_cast<double>(end - begin), std::round(r.duration_s * fs)) << i;
    for (std::size_t k = begin; k < end; k += 97) {
      const double t = static_cast<double>(k - begin) / fs;
      EXPECT_NEAR(e.u[k], r.offset_V + r.amplitude_V * std::sin(2.0 * std::numbers::pi * r.frequency_Hz * t), 1e-9);
    }
  }
  EXPECT_NEAR(series_duration_s(steps), total, 1e-9);
  EXPECT_LT(total, 45.0);  // about 36 s with the default plan
  BanningPlanOptions too_long = plan;
  too_long.frequencies_Hz.assign(200, 100.0);
  EXPECT_EQ(field_of([&] { banning_series(too_long); }), "banning-series");
  BanningPlanOptions bad = plan;
  bad.hysteresis_frequency_Hz = -1.0;
  EXPECT_EQ(field_of([&] { banning_series(bad); }), "hysteresis_frequency_Hz");
}

TEST(CtlSeries, TrackerFollowsTheStepsFromTheCommands) {
  BanningPlanOptions plan;
  plan.offsets_V = {0.0};
  plan.small_amplitudes_V = {};
  plan.amplitudes_V = {};
  plan.frequencies_Hz = {1000.0};
  const auto steps = banning_series(plan);
  ASSERT_EQ(steps.size(), 4u);
  SeriesTracker tracker(steps, 1e-4);
  EXPECT_FALSE(tracker.on_command(100, false));  // before the series
  EXPECT_FALSE(tracker.started());
  std::vector<std::size_t> entered;
  std::int64_t seq = 101;
  for (; !tracker.finished(); ++seq) {
    if (seq % 50 == 7) continue;  // commands lost on the way
    const bool experiment = !tracker.started() || seq < tracker.end_tick();
    if (const auto s = tracker.on_command(seq, experiment)) entered.push_back(*s);
  }
  EXPECT_EQ(entered, (std::vector<std::size_t>{0, 1, 2, 3}));
  EXPECT_EQ(*tracker.first_tick(), 101);
  // 20 periods at 50 Hz + 2 s + 50 periods at 1 kHz (400 V of path at 2 V) + 100 periods.
  EXPECT_EQ(tracker.end_tick() - 101, 4000 + 20000 + 500 + 1000);
  EXPECT_FALSE(tracker.ended_early());

  SeriesTracker stopped(steps, 1e-4);
  stopped.on_command(10, true);
  stopped.on_command(11, true);
  stopped.on_command(12, false);
  EXPECT_TRUE(stopped.ended_early());
  EXPECT_FALSE(stopped.finished());
}
