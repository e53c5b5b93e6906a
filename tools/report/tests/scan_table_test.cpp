// The scan table (scan_log, scan_figures, scan_output): a log of a generated scan is written with
// lcm::LogFile, its events read back, the figures checked against the generator's own truth, and
// hystloop-report --scan run on it end to end.
//
// The generated run (10 kHz, 10 s; e = y_ref - y alternates its sign every tick, so that a
// stretch of constant magnitude m has RMS m and max m):
//   0.0 s            no reference
//   0.95 s           SET_LEARNING off
//   1.0 s            trajectory A: triangle 1 µm at 50 Hz (200-tick period), blend 0.2 s: taken
//   1.0 .. 1.7 s     |e| = 100 nm (the approach and settling the table skips: blend + 0.5 s)
//   1.7 .. 4.0 s     |e| = 8 nm; clamped ticks at 1.1 s (5 saturated), 2.0 s (3 slew-limited),
//                    2.5 s (1 both); 2 late ticks at 3.0 s
//   4.0 s, 4.02 s    SET_LEARNING on, then reset: the segment measured starts at 4.02 s
//   4.02 .. 7.0 s    |e| = 1 nm + 7 nm * 0.5^p in period p after 4.02 s: converged after 6 periods
//   7.0 s            trajectory B: sine 1 µm at 10 Hz, refused (A runs on)
//   8.0 s            DISARM: nothing after it belongs to a reference
// Every request is sent 3 times (as hystloop-ctl does); the compensator reports once a second
// and right after each verdict.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include "hystloop/control_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/sim_truth_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/message_storage.hpp"
#include "log_reader.hpp"
#include "log_test_support.hpp"
#include "scan_figures.hpp"
#include "scan_log.hpp"
#include "scan_output.hpp"

namespace fs = std::filesystem;
using namespace hystloop;
using namespace hystloop::report;
using namespace hystloop::test;

namespace {

constexpr std::int64_t kT0 = 1'700'000'000'000'000;  // the first tick [us]
constexpr std::int64_t kTicks = 100'000;             // 10 s at 10 kHz
constexpr std::int64_t kBlock = 20;
constexpr std::int64_t kPeriod = 200;  // 50 Hz
constexpr std::int64_t kVersionA = 1001, kVersionB = 1002;
constexpr std::int32_t kSaturated = sensor_block_t::SATURATED;
constexpr std::int32_t kSlewLimited = sensor_block_t::SLEW_LIMITED;

std::int64_t at(double t_s) { return kT0 + static_cast<std::int64_t>(std::llround(t_s * 1e6)); }
std::int64_t tick_of(double t_s) { return static_cast<std::int64_t>(std::llround(t_s * 1e4)); }
double t_of(std::int64_t k) { return static_cast<double>(k) * 1e-4; }

// |e| of tick k (0: no reference).
double magnitude(std::int64_t k) {
  if (k < tick_of(1.0)) return 0.0;
  if (k < tick_of(1.7)) return 100e-9;
  if (k < tick_of(4.02)) return 8e-9;
  if (k < tick_of(7.0)) {
    const std::int64_t period = (k - tick_of(4.02)) / kPeriod;  // whole periods since the reset
    return 1e-9 + 7e-9 * std::pow(0.5, static_cast<double>(period));
  }
  return 3e-9;
}
std::int32_t flags(std::int64_t k) {
  std::int32_t f = sensor_block_t::SIMULATED;
  if (k >= tick_of(1.1) && k < tick_of(1.1) + 5) f |= sensor_block_t::SATURATED;
  if (k >= tick_of(2.0) && k < tick_of(2.0) + 3) f |= sensor_block_t::SLEW_LIMITED;
  if (k == tick_of(2.5)) f |= kSaturated | kSlewLimited;
  if (k == tick_of(3.0) || k == tick_of(3.0) + 1) f |= sensor_block_t::LATE_COMMAND;
  if (k >= tick_of(8.0) + 100) f |= sensor_block_t::SAFE_STATE;
  return f;
}

template <class T>
void add(std::vector<Event>& events, std::int64_t t, const std::string& channel, const T& msg, int copies = 1) {
  for (int i = 0; i < copies; ++i) events.push_back(event(t + std::int64_t{2000} * i, channel, msg));
}

control_t control(std::int64_t id, std::int8_t command, std::int8_t learning = 0) {
  control_t c{};
  c.utime = kT0;
  c.request_id = id;
  c.command = command;
  c.target = command == control_t::SET_LEARNING ? "compensator" : "bridge";
  c.learning = learning;
  return c;
}

trajectory_t trajectory(std::int64_t version, std::int8_t shape, double frequency_hz) {
  trajectory_t t{};
  t.utime = kT0;
  t.version = version;
  t.shape = shape;
  t.amplitude_m = 1e-6;
  t.frequency_Hz = frequency_hz;
  t.blend_s = 0.2;
  return t;
}

service_status_t compensator_status(double t_s) {
  service_status_t s{};
  s.utime = at(t_s);
  s.process = "compensator";
  s.host = "h";
  s.pid = 42;
  s.state = service_status_t::HEALTHY;
  s.start_utime = kT0;
  s.loop_p50_us = s.loop_p99_us = s.loop_max_us = std::nan("");
  s.latency_p50_us = s.latency_p99_us = s.latency_max_us = std::nan("");
  std::vector<std::pair<std::string, std::int64_t>> c;
  if (t_s > 1.0) c.emplace_back("trajectory_version", kVersionA);
  if (t_s > 7.0) c.emplace_back("trajectory_refused_version", kVersionB);
  c.emplace_back("learning_active", t_s > 4.0 ? 1 : 0);
  c.emplace_back("learning_periods", t_s > 4.0 ? static_cast<std::int64_t>((t_s - 4.02) * 50) : 0);
  c.emplace_back("learning_rms_pm", 1100);
  c.emplace_back("model_switches", t_s > 2.5 ? 1 : 0);                    // one in the off segment
  c.emplace_back("params_swapped", t_s > 5.5 ? 4 : (t_s > 2.5 ? 1 : 0));  // 3 more in the on segment
  for (auto& [name, value] : c) s.counter_names.push_back(name), s.counter_values.push_back(value);
  s.n_counters = static_cast<std::int32_t>(c.size());
  std::string detail;
  if (t_s > 1.0 && t_s < 1.5) detail += "trajectory 1001 taken: corners rounded over 1.16 ms; ";
  if (t_s > 7.0 && t_s < 7.5) detail += "trajectory 1002 refused: its feedforward needs 1e+05 V/s; at 10 Hz; ";
  detail += std::string("stage 1722 Hz zeta 0.0938; mode ") + (t_s > 2.5 ? "pi" : "mem") + ", params v3 c1=1";
  s.detail = detail;
  return s;
}

// The simulated stage's true position in the generated log (write_log's `truth`): its error
// y_ref - y_true is half the measured one, same sign.
struct TruthBlocks {
  bool on = false;
  std::int64_t missing_block = -1;  // the first seq of a block whose truth is left out
};

void write_log(const fs::path& file, TruthBlocks truth = {}) {
  std::vector<Event> events;
  sensor_block_t sb{};
  reserve_storage(sb);
  sim_truth_t tb{};
  for (std::int64_t first = 0; first < kTicks; first += kBlock) {
    begin_block(tb, first, at(t_of(first)));
    begin_block(sb, first, at(t_of(first)), 1e-4);
    for (std::int64_t k = first; k < first + kBlock; ++k) {
      const double m = magnitude(k);
      SensorTick t{};
      t.y_ref_m = m > 0.0 ? 1e-6 * std::sin(static_cast<double>(k) / 100.0) : std::nan("");
      t.y_m = (m > 0.0 ? t.y_ref_m : 0.0) - ((k % 2) != 0 ? m : -m);
      t.flags = flags(k);
      append_tick(sb, t);
      const double y_true_m = m > 0.0 ? t.y_ref_m - 0.5 * (t.y_ref_m - t.y_m) : t.y_m;
      append_tick(tb, std::span(&y_true_m, 1));
    }
    sb.buffer_depth_ticks = 400;
    const std::int64_t received = at(t_of(first + kBlock - 1));  // with its last tick
    // Every other truth block before its sensor block: the reader pairs them either way.
    const bool truth_first = (first / kBlock) % 2 == 1;
    const bool with_truth = truth.on && first != truth.missing_block;
    if (with_truth && truth_first) add(events, received, "HX_SIM_TRUTH", tb);
    add(events, received, "HX_SENSOR", sb);
    if (with_truth && !truth_first) add(events, received, "HX_SIM_TRUTH", tb);
  }
  add(events, at(0.95), "HX_CONTROL", control(1, control_t::SET_LEARNING, control_t::LEARNING_OFF), 3);
  add(events, at(1.0), "HX_TRAJECTORY", trajectory(kVersionA, trajectory_t::TRIANGLE, 50.0), 3);
  add(events, at(4.0), "HX_CONTROL", control(2, control_t::SET_LEARNING, control_t::LEARNING_ON), 3);
  add(events, at(4.02), "HX_CONTROL", control(3, control_t::SET_LEARNING, control_t::LEARNING_RESET), 3);
  add(events, at(7.0), "HX_TRAJECTORY", trajectory(kVersionB, trajectory_t::SINE, 10.0), 3);
  add(events, at(8.0), "HX_CONTROL", control(4, control_t::DISARM), 3);
  for (const double t : {0.5, 1.01, 1.5, 2.5, 3.5, 4.5, 5.5, 6.5, 6.99, 7.01, 7.5, 8.5, 9.5}) {
    add(events, at(t), "HX_STATUS", compensator_status(t));
  }
  write_events(file, events);
}

struct Truth {  // figures of ticks [from, to) computed from the generator
  double rms = 0.0, max = 0.0;
  std::size_t clamped = 0, saturated = 0, slew = 0, late = 0;
};
Truth truth(double from_s, double to_s) {
  Truth x;
  double sum = 0.0;
  std::size_t n = 0;
  for (std::int64_t k = tick_of(from_s); k < tick_of(to_s); ++k) {
    const std::int32_t f = flags(k);
    x.clamped += (f & (kSaturated | kSlewLimited)) != 0 ? 1 : 0;
    x.saturated += (f & sensor_block_t::SATURATED) != 0 ? 1 : 0;
    x.slew += (f & sensor_block_t::SLEW_LIMITED) != 0 ? 1 : 0;
    x.late += (f & sensor_block_t::LATE_COMMAND) != 0 ? 1 : 0;
    sum += magnitude(k) * magnitude(k), ++n;
    x.max = std::max(x.max, magnitude(k));
  }
  x.rms = std::sqrt(sum / static_cast<double>(n));
  return x;
}

class ScanLog : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("scan_table_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    write_log(dir_ / "scan.lcmlog");
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static fs::path log() { return dir_ / "scan.lcmlog"; }
  static fs::path dir_;
};
fs::path ScanLog::dir_;

}  // namespace

TEST_F(ScanLog, MeasuresAgainstTheSimulatorsTruePositionWhenTheLogHasIt) {
  write_log(dir_ / "truth.lcmlog", {true, -1});
  const ChannelNames channels("HX_");
  const RunData run = read_logs({dir_ / "truth.lcmlog"}, channels);
  EXPECT_EQ(run.truth_ticks, static_cast<std::uint64_t>(kTicks));
  EXPECT_EQ(run.undecodable, 0u);
  const ScanResult scan =
      compute_scan(run, read_scan_events({dir_ / "truth.lcmlog"}, channels, "compensator"), ScanOptions{});
  ASSERT_TRUE(scan.references[0].off && scan.references[0].on);
  for (const auto* f : {&*scan.references[0].off, &*scan.references[0].on}) {
    EXPECT_EQ(f->true_ticks, f->analysed_ticks);
    ASSERT_TRUE(f->rms_true_m && f->max_abs_true_m);
    EXPECT_NEAR(*f->rms_true_m, 0.5 * *f->rms_m, 1e-15);
    EXPECT_NEAR(*f->max_abs_true_m, 0.5 * *f->max_abs_m, 1e-15);
  }
  EXPECT_NE(scan_table(scan).find("| triangle 1 µm 50 Hz | off | 8.00 | 8.00 | 8.0 | 4.00 | 4.0 | 9 |"),
            std::string::npos)
      << scan_table(scan);

  // Without the truth of one analysed block the segment gets no true figures (they would cover
  // other ticks than the measured ones); the other segment keeps them.
  const std::int64_t missing = (tick_of(5.0) / kBlock) * kBlock;
  write_log(dir_ / "truth_gap.lcmlog", {true, missing});
  const RunData gap = read_logs({dir_ / "truth_gap.lcmlog"}, channels);
  EXPECT_EQ(gap.truth_ticks, static_cast<std::uint64_t>(kTicks - kBlock));
  const ScanResult with_gap =
      compute_scan(gap, read_scan_events({dir_ / "truth_gap.lcmlog"}, channels, "compensator"), ScanOptions{});
  const SegmentFigures& on = *with_gap.references[0].on;
  EXPECT_EQ(on.true_ticks, on.analysed_ticks - static_cast<std::size_t>(kBlock));
  EXPECT_FALSE(on.rms_true_m || on.max_abs_true_m);
  EXPECT_TRUE(with_gap.references[0].off->rms_true_m);
}

TEST(ScanFigures, PeriodsToConvergeFindsTheFirstPeriodOfTheSettledTail) {
  std::vector<double> r{9, 7, 5, 3, 1.3, 1.0, 1.1, 0.9, 1.0, 1.05, 1.0, 0.95, 1.0, 1.1, 1.0};
  EXPECT_EQ(periods_to_converge(r, 1.2, 10), 5u);  // 1.3 > 1.2 x median 1.0: the tail starts after it
  EXPECT_EQ(periods_to_converge(std::vector<double>(12, 2.0), 1.2, 10), 0u);
  EXPECT_FALSE(periods_to_converge(std::vector<double>(9, 2.0), 1.2, 10));  // fewer than the tail
  r.push_back(5.0);                                                         // a late bump: not settled
  EXPECT_FALSE(periods_to_converge(r, 1.2, 10));
  EXPECT_DOUBLE_EQ(*median_of_last({1, 5, 3, 2}, 3), 3.0);
  EXPECT_DOUBLE_EQ(*median_of_last({1, 5, 3, 2}, 10), 2.5);
  EXPECT_FALSE(median_of_last({}, 3));
}

TEST(ScanFigures, ParsesTheCompensatorsDetail) {
  const std::string d =
      "trajectory 7 refused: needs 1e5 V/s (limit; servo); at 10 Hz; learning a 200-tick period; "
      "stage 1722 Hz; mode pi, params v3";
  EXPECT_EQ(verdict_text(d, 7, "refused"), "needs 1e5 V/s (limit; servo); at 10 Hz");
  EXPECT_EQ(verdict_text(d, 8, "refused"), "");
  EXPECT_EQ(compensator_mode(d), "pi");
  EXPECT_EQ(compensator_mode("stage 1 Hz; model x"), "");
}

TEST_F(ScanLog, ReadsEachRequestAndTrajectoryOnce) {
  const ScanEvents e = read_scan_events({log()}, ChannelNames("HX_"), "compensator");
  ASSERT_EQ(e.trajectories.size(), 2u);
  EXPECT_EQ(e.trajectories[0].shape, "triangle");
  EXPECT_EQ(e.trajectories[0].recv_utime, at(1.0));
  EXPECT_EQ(e.trajectories[1].version, kVersionB);
  ASSERT_EQ(e.controls.size(), 4u);
  EXPECT_EQ(e.controls[2].kind, ScanControl::Kind::kLearningReset);
  EXPECT_EQ(e.controls[3].kind, ScanControl::Kind::kStop);
  EXPECT_EQ(e.compensator.size(), 13u);
  EXPECT_EQ(periodic_trajectories(e), 2u);
}

TEST_F(ScanLog, MeasuresEachReferenceWithLearningOffAndOn) {
  const ChannelNames channels("HX_");
  const RunData run = read_logs({log()}, channels);
  const ScanResult scan = compute_scan(run, read_scan_events({log()}, channels, "compensator"), ScanOptions{});
  ASSERT_EQ(scan.references.size(), 2u);
  const ReferenceFigures& a = scan.references[0];
  EXPECT_EQ(a.label(), "triangle 1 µm 50 Hz");
  EXPECT_EQ(a.verdict, Verdict::kAccepted);
  EXPECT_EQ(a.verdict_detail, "corners rounded over 1.16 ms");
  ASSERT_TRUE(a.off && a.on);

  const SegmentFigures& off = *a.off;
  EXPECT_EQ(off.learning, LearningState::kOff);
  EXPECT_NEAR(off.start_s, 1.0, 1e-6);
  EXPECT_NEAR(off.end_s, 4.0, 1e-6);
  EXPECT_NEAR(off.analysed_from_s, 1.7, 1e-6);  // blend 0.2 s + settle 0.5 s
  const Truth t_off = truth(1.7, 4.0), whole_off = truth(1.0, 4.0);
  EXPECT_NEAR(*off.rms_m, t_off.rms, 1e-15);
  EXPECT_NEAR(*off.max_abs_m, 8e-9, 1e-15);
  EXPECT_NEAR(*off.rms_last_m, 8e-9, 1e-15);
  EXPECT_EQ(off.clamped_ticks, whole_off.clamped);  // the approach counts: 5 + 3 + 1
  EXPECT_EQ(off.clamped_ticks, 9u);
  EXPECT_EQ(off.saturated_ticks, 6u);
  EXPECT_EQ(off.slew_limited_ticks, 4u);
  EXPECT_EQ(off.late_ticks, 2u);
  EXPECT_EQ(off.period_ticks, kPeriod);
  EXPECT_EQ(off.period_rms_m.size(), 150u);  // 3 s of 20 ms periods
  EXPECT_EQ(off.mode, "pi");
  EXPECT_EQ(off.model_switches, 1);

  const SegmentFigures& on = *a.on;
  EXPECT_EQ(on.learning, LearningState::kOn);
  EXPECT_NEAR(on.start_s, 4.02, 1e-6);  // the reset, not the "on" 20 ms before it
  EXPECT_NEAR(on.end_s, 7.0, 1e-6);     // the refused trajectory B ends the segment
  ASSERT_EQ(on.period_rms_m.size(), 149u);
  for (std::size_t p = 0; p < 8; ++p) EXPECT_NEAR(on.period_rms_m[p], 1e-9 + 7e-9 * std::pow(0.5, p), 1e-15);
  EXPECT_EQ(on.periods_to_converge, 6u);  // 1 + 7 x 0.5^6 = 1.11 nm is the first within 1.2 nm
  EXPECT_NEAR(*on.rms_m, truth(4.52, 7.0).rms, 1e-15);
  EXPECT_NEAR(*on.rms_last_m, 1e-9, 1e-14);
  EXPECT_EQ(on.clamped_ticks, 0u);
  EXPECT_NEAR(*on.learned_rms_m, 1.1e-9, 1e-15);
  EXPECT_EQ(on.params_swaps, 3);

  const ReferenceFigures& b = scan.references[1];
  EXPECT_EQ(b.verdict, Verdict::kRefused);
  EXPECT_EQ(b.verdict_detail, "its feedforward needs 1e+05 V/s; at 10 Hz");
  EXPECT_FALSE(b.off || b.on);
  EXPECT_EQ(scan.refused(), 1u);

  const std::string table = scan_table(scan);
  EXPECT_NE(table.find("| triangle 1 µm 50 Hz | off | 8.00 | 8.00 | 8.0 | — | — | 9 | 2 | 150 |"), std::string::npos)
      << table;
  EXPECT_NE(table.find("| triangle 1 µm 50 Hz | on |"), std::string::npos) << table;
  EXPECT_NE(table.find("**refused**: its feedforward needs 1e+05 V/s; at 10 Hz"), std::string::npos) << table;
}

// The safe-state ticks a segment ends with when a DISARM ends it are the stop's: the bridge ran
// them after the request, though a block's ticks are dated back from its arrival. Safe ticks
// before them (a watchdog trip mid-line) still count.
TEST_F(ScanLog, TheSafeTicksOfTheStopAreNotTheSegments) {
  const ChannelNames channels("HX_");
  RunData run = read_logs({log()}, channels);
  ScanEvents events = read_scan_events({log()}, channels, "compensator");
  // Without the refused B at 7 s, A's learning-on segment runs from 4.02 s to the DISARM at 8 s.
  std::erase_if(events.trajectories, [](const ScanTrajectory& t) { return t.version == kVersionB; });
  std::size_t trailing = 0;
  for (auto& sample : run.samples) {
    const bool trip = sample.seq >= tick_of(6.0) && sample.seq < tick_of(6.0) + 3;
    const bool stop = sample.recv_utime >= at(7.9985) && sample.recv_utime < at(8.0);
    if (trip || stop) sample.flags |= sensor_block_t::SAFE_STATE;
    trailing += stop ? 1 : 0;
  }
  ASSERT_GT(trailing, 10u);
  const ScanResult scan = compute_scan(run, events, ScanOptions{});
  ASSERT_EQ(scan.references.size(), 1u);
  ASSERT_TRUE(scan.references[0].on);
  const SegmentFigures& on = *scan.references[0].on;
  EXPECT_NEAR(on.end_s, 8.0, 1e-6);
  EXPECT_EQ(on.safe_ticks, 3u);
  EXPECT_EQ(on.ticks, static_cast<std::size_t>(tick_of(8.0) - tick_of(4.02)) - trailing);
}

TEST_F(ScanLog, InfersTheLearningStateWithoutRequests) {
  const ChannelNames channels("HX_");
  const RunData run = read_logs({log()}, channels);
  ScanEvents events = read_scan_events({log()}, channels, "compensator");
  std::erase_if(events.controls, [](const ScanControl& c) { return c.kind != ScanControl::Kind::kStop; });
  const ScanResult scan = compute_scan(run, events, ScanOptions{});
  // One segment 1.0 .. 7.0 s; the compensator's last report in it says it learns.
  ASSERT_TRUE(scan.references[0].on);
  EXPECT_FALSE(scan.references[0].off);
  EXPECT_NEAR(scan.references[0].on->end_s, 7.0, 1e-6);
}

TEST_F(ScanLog, ReportWritesTheScanTable) {
  const fs::path out = dir_ / "out";
  const ToolRun r = run_tool(HYSTLOOP_REPORT_EXE, log().string() + " --out " + out.string() + " --no-plots", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("scan, 2 reference(s), 1 refused"), std::string::npos) << r.out;  // two periodic: automatic
  ASSERT_TRUE(fs::exists(out / "scan.md"));
  std::ifstream in(out / "scan.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["references_refused"], 1);
  const auto& a = j["references"][0];
  EXPECT_EQ(a["shape"], "triangle");
  EXPECT_EQ(a["verdict"], "accepted");
  EXPECT_NEAR(a["learning_off"]["rms_error_m"].get<double>(), truth(1.7, 4.0).rms, 1e-15);
  EXPECT_EQ(a["learning_off"]["clamped_ticks"], 9);
  EXPECT_EQ(a["learning_on"]["periods_to_converge"], 6);
  EXPECT_EQ(a["learning_on"]["period_rms_m"].size(), 149u);
  EXPECT_EQ(j["references"][1]["verdict"], "refused");
  EXPECT_TRUE(j["references"][1]["learning_on"].is_null());

  // --no-scan writes none; --scan on a log without periodic trajectories is an error.
  const fs::path out2 = dir_ / "out2";
  ASSERT_EQ(std::system((std::string(HYSTLOOP_REPORT_EXE) + " " + log().string() + " --out " + out2.string() +
                         " --no-plots --no-scan --quiet")
                            .c_str()),
            0);
  EXPECT_FALSE(fs::exists(out2 / "scan.json"));
}
