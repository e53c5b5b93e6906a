// The scan-path table (path_log, path_figures, path_output, path_report) and hystloop-report --axis:
// a log of a 2-axis stage is written with lcm::LogFile, measured by the figures' functions and by
// hystloop-report end to end, and checked against the generator's own truth.
//
// The generated run (10 kHz, 1 s, blocks of 20 ticks carrying x and y, a truth block after each):
//   0.20 s   raster v77 on HX_SCAN (3 copies): 8 lines of 1 µm x 0.5 µm at 50 lines/s, x fast,
//            y stepping, corner_s 0 (the compensator's choice: 1.2345 ms here); the compensator
//            takes it from loop time 0.30004567 s and prints "0.3000" (0.1 ms: as it does)
//   0.54 s   Lissajous v78: x 0.3 µm 20 Hz, y 0.2 µm 15 Hz, 0.2 s, from 0.65003333 s ("0.6500")
//   0.90 s   raster v79, refused
// y_ref of each axis is the path's own reference (the raster's until 0.55 s, then the
// Lissajous figure's); the true position is r - e_true with e_true = +-0.5 nm on x and +-0.8 nm
// on y (the sign alternating tick by tick: RMS and max are the magnitude), +-0.6 and +-0.9 nm from
// 0.55 s on; the measured y_m is r - e with e = +-3 nm on x, +-4 nm on y throughout.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include "hystloop/mem_params_t.hpp"
#include "hystloop/scan_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/sim_truth_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/message_storage.hpp"
#include "log_test_support.hpp"
#include "path_figures.hpp"
#include "path_log.hpp"
#include "path_output.hpp"

namespace fs = std::filesystem;
using namespace hystloop;
using namespace hystloop::report;
using namespace hystloop::test;

namespace {

constexpr std::int64_t kT0 = 1'700'000'000'000'000;  // the first tick [us]
constexpr double kDt = 1e-4;
constexpr std::int64_t kTicks = 10'000;
constexpr std::int64_t kBlock = 20;
constexpr std::int64_t kRasterVersion = 77, kLissajousVersion = 78, kRefusedVersion = 79;
constexpr double kRasterStartS = 0.30004567, kLissajousStartS = 0.65003333;
constexpr double kCornerS = 1.2345e-3;
constexpr double kSwitchS = 0.55;  // y_ref follows the Lissajous figure from here
// A reference found exactly leaves only rounding: far below a picometre.
constexpr double kExactM = 1e-14;

std::int64_t at(double t_s) { return kT0 + static_cast<std::int64_t>(std::llround(t_s * 1e6)); }
double t_of(std::int64_t k) { return static_cast<double>(k) * kDt; }

RasterSpec raster() {
  RasterSpec r;
  r.fast_axis = 0;
  r.slow_axis = 1;
  r.width_m = 1e-6;
  r.height_m = 0.5e-6;
  r.lines = 8;
  r.line_rate_hz = 50.0;
  r.corner_s = kCornerS;
  r.settle_s = 0.05;
  r.centre_m = {0.1e-6, -0.2e-6, 0.0};
  r.start_s = kRasterStartS;
  return r;
}

LissajousSpec lissajous() {
  LissajousSpec l;
  l.amplitude_m = {0.3e-6, 0.2e-6, 0.0};
  l.frequency_hz = {20.0, 15.0, 0.0};
  l.phase_rad = {0.0, 0.3, 0.0};
  l.centre_m = {0.0, 0.1e-6, 0.0};
  l.duration_s = 0.2;
  l.start_s = kLissajousStartS;
  return l;
}

AxisPositions reference(std::int64_t k) {
  const double t = t_of(k);
  return t < kSwitchS ? evaluate(raster(), t) : evaluate(lissajous(), t);
}
double sign(std::int64_t k) { return (k % 2) != 0 ? 1.0 : -1.0; }
double true_error(std::int64_t k, std::size_t axis) {
  const bool late = t_of(k) >= kSwitchS;
  return sign(k) * (axis == 0 ? (late ? 0.6e-9 : 0.5e-9) : (late ? 0.9e-9 : 0.8e-9));
}
double measured_error(std::int64_t k, std::size_t axis) { return sign(k) * (axis == 0 ? 3e-9 : 4e-9); }

scan_t scan_message(std::int64_t version, std::int8_t path) {
  scan_t s{};
  s.utime = kT0;
  s.version = version;
  s.path = path;
  s.decouple = true;
  s.blend_s = 0.05;
  if (path == scan_t::RASTER) {
    const RasterSpec r = raster();
    s.fast_axis = 0;
    s.slow_axis = 1;
    s.width_m = r.width_m;
    s.height_m = r.height_m;
    s.lines = r.lines;
    s.line_rate_Hz = r.line_rate_hz;
    s.slow_mode = scan_t::STEPS;
    s.corner_s = 0.0;  // the compensator's choice
    s.settle_s = r.settle_s;
    for (std::size_t i = 0; i < 3; ++i) s.centre_m[i] = r.centre_m[i];
  } else {
    const LissajousSpec l = lissajous();
    for (std::size_t i = 0; i < 3; ++i) {
      s.amplitude_m[i] = l.amplitude_m[i];
      s.frequency_Hz[i] = l.frequency_hz[i];
      s.phase_rad[i] = l.phase_rad[i];
      s.centre_m[i] = l.centre_m[i];
    }
    s.duration_s = l.duration_s;
  }
  return s;
}

service_status_t compensator_status(double t_s, std::int64_t version, const std::string& verdict,
                                    std::int64_t refused = 0) {
  service_status_t s{};
  s.utime = at(t_s);
  s.process = "compensator";
  s.host = "h";
  s.pid = 42;
  s.state = service_status_t::HEALTHY;
  s.start_utime = kT0;
  s.loop_p50_us = s.loop_p99_us = s.loop_max_us = std::nan("");
  s.latency_p50_us = s.latency_p99_us = s.latency_max_us = std::nan("");
  const std::vector<std::pair<std::string, std::int64_t>> c{{"trajectory_version", version},
                                                            {"trajectory_refused_version", refused}};
  for (const auto& [name, value] : c) s.counter_names.push_back(name), s.counter_values.push_back(value);
  s.n_counters = static_cast<std::int32_t>(c.size());
  s.detail = "mode mem, params v0; " + verdict + (verdict.empty() ? "" : "; ") + "stage 1620 Hz zeta 0.1 inverted";
  return s;
}

struct LogOptions {
  bool truth = true;
  int axes = 2;
};

void write_log(const fs::path& file, const LogOptions& o = {}) {
  std::vector<Event> events;
  sensor_block_t sb{};
  reserve_storage(sb);
  sim_truth_t tb{};
  reserve_storage(tb);
  for (std::int64_t first = 0; first < kTicks; first += kBlock) {
    begin_block(sb, first, at(t_of(first)), kDt, o.axes);
    begin_block(tb, first, at(t_of(first)), o.axes);
    for (std::int64_t k = first; k < first + kBlock; ++k) {
      const AxisPositions r = reference(k);
      std::array<SensorTick, 2> ticks{};
      std::array<double, 2> y_true{};
      for (std::size_t a = 0; a < static_cast<std::size_t>(o.axes); ++a) {
        ticks[a].u_V = 10.0 * r[a] / 1e-6;
        ticks[a].u_ff_V = ticks[a].u_V;
        ticks[a].y_ref_m = r[a];
        ticks[a].y_m = r[a] - measured_error(k, a);
        ticks[a].flags = sensor_block_t::SIMULATED;
        y_true[a] = r[a] - true_error(k, a);
      }
      ASSERT_TRUE(append_tick(sb, std::span<const SensorTick>(ticks).first(static_cast<std::size_t>(o.axes))));
      ASSERT_TRUE(append_tick(tb, std::span<const double>(y_true).first(static_cast<std::size_t>(o.axes))));
    }
    sb.buffer_depth_ticks = 400;
    const std::int64_t received = at(t_of(first + kBlock - 1));  // with its last tick
    events.push_back(event(received, "HX_SENSOR", sb));
    if (o.truth) events.push_back(event(received, "HX_SIM_TRUTH", tb));
  }
  for (int copy = 0; copy < 3; ++copy) {  // hystloop-ctl sends each path 3 times
    events.push_back(
        event(at(0.20) + copy * std::int64_t{2000}, "HX_SCAN", scan_message(kRasterVersion, scan_t::RASTER)));
    events.push_back(
        event(at(0.54) + copy * std::int64_t{2000}, "HX_SCAN", scan_message(kLissajousVersion, scan_t::LISSAJOUS)));
    events.push_back(
        event(at(0.90) + copy * std::int64_t{2000}, "HX_SCAN", scan_message(kRefusedVersion, scan_t::RASTER)));
  }
  events.push_back(event(at(0.1), "HX_STATUS", compensator_status(0.1, 0, "")));
  events.push_back(event(at(0.201), "HX_STATUS",
                         compensator_status(0.201, kRasterVersion,
                                            "trajectory 77 taken: scan taken by 2 axes, decoupled: from loop time "
                                            "0.3000 s to 0.5100 s")));
  events.push_back(event(at(0.5), "HX_STATUS", compensator_status(0.5, kRasterVersion, "")));
  events.push_back(event(at(0.541), "HX_STATUS",
                         compensator_status(0.541, kLissajousVersion,
                                            "trajectory 78 taken: scan taken by 2 axes, decoupled: from loop time "
                                            "0.6500 s to 0.8500 s")));
  events.push_back(event(at(0.901), "HX_STATUS",
                         compensator_status(0.901, kLissajousVersion,
                                            "trajectory 79 refused: axis x: exceeds its slew limit", kRefusedVersion)));
  mem_params_t y_params{};  // a parameter set of y's hysteresis: --axis y shows it, x does not
  y_params.utime = kT0;
  y_params.version = 1;
  y_params.c1 = 2e-9;
  y_params.c2 = 1e-12;
  y_params.c3 = 1.2;
  y_params.valid = true;
  y_params.axis = 1;
  y_params.source = "test";
  events.push_back(event(at(0.05), "HX_PARAMS", y_params));
  write_events(file, events);
}

// The figures the generator fixed: RMS and max of +-m are m.
void expect_axis(const nlohmann::json& axis, const char* name, double magnitude_m, std::size_t ticks) {
  EXPECT_EQ(axis.at("axis"), name);
  EXPECT_EQ(axis.at("ticks").get<std::size_t>(), ticks) << name;
  EXPECT_NEAR(axis.at("rms_error_m").get<double>(), magnitude_m, kExactM) << name;
  EXPECT_NEAR(axis.at("max_abs_error_m").get<double>(), magnitude_m, kExactM) << name;
  EXPECT_LT(axis.at("reference_mismatch_m").get<double>(), kExactM) << name;
}

nlohmann::json read_json(const fs::path& file) { return nlohmann::json::parse(slurp(file)); }

// The rows of a CSV as maps of column -> text (no quoted commas in the columns read here).
std::vector<std::map<std::string, std::string>> read_csv(const fs::path& file) {
  std::istringstream in(slurp(file));
  std::string line;
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
  auto split = [](const std::string& s) {
    std::vector<std::string> out;
    std::string field;
    bool quoted = false;
    for (const char c : s) {
      if (c == '"') {
        quoted = !quoted;
      } else if (c == ',' && !quoted) {
        out.push_back(field), field.clear();
      } else {
        field += c;
      }
    }
    out.push_back(field);
    return out;
  };
  while (std::getline(in, line)) {
    if (header.empty()) {
      header = split(line);
      continue;
    }
    const auto fields = split(line);
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < header.size() && i < fields.size(); ++i) row[header[i]] = fields[i];
    rows.push_back(row);
  }
  return rows;
}

class PathReport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("path_report_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    write_log(dir_ / "xy.lcmlog");
  }
  static void TearDownTestSuite() {
    if (std::getenv("HYSTLOOP_KEEP_TEST_OUTPUT") == nullptr) fs::remove_all(dir_);
  }
  static ToolRun report(const std::string& args, const std::string& out) {
    fs::create_directories(dir_ / (out + "_scratch"));
    return run_tool(HYSTLOOP_REPORT_EXE, args + " --out " + (dir_ / out).string(), dir_ / (out + "_scratch"));
  }
  static fs::path dir_;
};
fs::path PathReport::dir_;

// A compensator report as read_path_events keeps it.
ScanCompensatorStatus report_at(double t_s, const std::string& detail, std::int64_t version,
                                std::optional<std::int64_t> refused = std::nullopt) {
  ScanCompensatorStatus s;
  s.recv_utime = at(t_s);
  s.detail = detail;
  s.trajectory_version = version;
  s.trajectory_refused_version = refused;
  return s;
}

// Ticks of every axis as read_path_ticks gives them, straight from the generator.
std::vector<PathTick> generated_ticks(std::int64_t from, std::int64_t to) {
  std::vector<PathTick> out;
  for (std::int64_t k = from; k < to; ++k) {
    PathTick t;
    t.seq = k;
    t.recv_utime = at(t_of(k));
    t.dt_s = kDt;
    t.axes = 2;
    const AxisPositions r = reference(k);
    for (std::size_t a = 0; a < 2; ++a) {
      t.y_ref_m[a] = r[a];
      t.y_m[a] = r[a] - measured_error(k, a);
      t.y_true_m[a] = r[a] - true_error(k, a);
    }
    out.push_back(t);
  }
  return out;
}

}  // namespace

TEST(PathFigures, TheCornerAndTheStartComeFromTheLoggedReference) {
  const std::vector<PathTick> ticks = generated_ticks(0, static_cast<std::int64_t>(kSwitchS / kDt));
  RasterSpec printed = raster();
  printed.corner_s = 0.0;
  printed.start_s = 0.3000;  // as the compensator prints it: 46 µs early
  const auto corner = raster_corner_from_reference(printed, ticks);
  ASSERT_TRUE(corner);
  EXPECT_NEAR(*corner, kCornerS, 1e-12);

  LoggedPath path;
  printed.corner_s = *corner;
  path.path = printed;
  const auto start = fit_start(path, ticks);
  ASSERT_TRUE(start);
  EXPECT_NEAR(*start, kRasterStartS, 1e-12);

  // A Lissajous figure's start alike; without any reference there is nothing to fit.
  LissajousSpec l = lissajous();
  l.start_s = 0.65;
  path.path = l;
  const std::vector<PathTick> late = generated_ticks(static_cast<std::int64_t>(kSwitchS / kDt), kTicks);
  const auto lissajous_start = fit_start(path, late);
  ASSERT_TRUE(lissajous_start);
  EXPECT_NEAR(*lissajous_start, kLissajousStartS, 1e-12);
  std::vector<PathTick> blind = late;
  for (PathTick& t : blind) t.y_ref_m = {kNoValue, kNoValue, kNoValue};
  EXPECT_FALSE(fit_start(path, blind));
}

TEST(PathFigures, EachAxisIsMeasuredAgainstItsOwnReferenceOverTheLines) {
  PathEvents events;
  LoggedPath p;
  p.recv_utime = at(0.2);
  p.version = kRasterVersion;
  RasterSpec sent = raster();
  sent.corner_s = 0.0;
  sent.start_s = 0.0;
  p.path = sent;
  events.paths.push_back(p);
  events.compensator.push_back(
      report_at(0.21, "trajectory 77 taken: scan taken by 2 axes: from loop time 0.3000 s to 0.51 s", kRasterVersion));
  std::vector<PathFigures> paths = decide_paths(events, kT0);
  ASSERT_EQ(paths.size(), 1u);
  ASSERT_TRUE(paths[0].measured()) << paths[0].skipped;
  EXPECT_EQ(paths[0].printed_start_s, 0.3);
  const std::vector<LoopWindow> windows = read_windows(paths);
  ASSERT_EQ(windows.size(), 1u);
  EXPECT_LE(windows[0].from_s, kRasterStartS - 0.001);
  EXPECT_GE(windows[0].to_s, kRasterStartS + 0.16 + 0.001);

  const std::vector<PathTick> ticks = generated_ticks(0, static_cast<std::int64_t>(kSwitchS / kDt));
  measure_path(paths[0], ticks);
  const PathFigures& f = paths[0];
  ASSERT_TRUE(f.measured()) << f.skipped;
  EXPECT_EQ(f.position, PositionSource::kTrue);
  EXPECT_EQ(f.expected_ticks, 1600u);  // 8 lines at 50 lines/s
  EXPECT_EQ(f.missing_ticks, 0u);
  EXPECT_FALSE(f.interrupted);
  ASSERT_EQ(f.per_axis.size(), 2u);
  EXPECT_EQ(f.per_axis[0].role, "fast");
  EXPECT_EQ(f.per_axis[1].role, "slow");
  EXPECT_NEAR(*f.per_axis[0].rms_m, 0.5e-9, kExactM);
  EXPECT_NEAR(*f.per_axis[1].rms_m, 0.8e-9, kExactM);
  EXPECT_NEAR(*f.per_axis[1].max_abs_m, 0.8e-9, kExactM);
  EXPECT_EQ(f.t_s.size(), 1600u);
  EXPECT_EQ(f.error_m[1].size(), 1600u);

  // Without the true position the measured one is used.
  std::vector<PathTick> measured_only = ticks;
  for (PathTick& t : measured_only) t.y_true_m = {kNoValue, kNoValue, kNoValue};
  std::vector<PathFigures> again = decide_paths(events, kT0);
  measure_path(again[0], measured_only);
  EXPECT_EQ(again[0].position, PositionSource::kMeasured);
  EXPECT_NEAR(*again[0].per_axis[0].rms_m, 3e-9, kExactM);
  EXPECT_NEAR(*again[0].per_axis[1].rms_m, 4e-9, kExactM);
}

TEST(PathFigures, ANewerTrajectoryEndsThePathWhereItIsReported) {
  PathEvents events;
  LoggedPath p;
  p.recv_utime = at(0.2);
  p.version = kRasterVersion;
  RasterSpec sent = raster();
  sent.start_s = 0.0;
  p.path = sent;
  events.paths.push_back(p);
  events.compensator.push_back(
      report_at(0.21, "trajectory 77 taken: scan: from loop time 0.3000 s to 0.51 s", kRasterVersion));
  events.compensator.push_back(report_at(0.40, "mode mem", kRasterVersion));
  events.compensator.push_back(report_at(0.42, "trajectory 80 taken: sine", 80));  // mid-raster
  std::vector<PathFigures> paths = decide_paths(events, kT0);
  ASSERT_EQ(paths[0].replaced_utime, at(0.42));
  measure_path(paths[0], generated_ticks(0, static_cast<std::int64_t>(kSwitchS / kDt)));
  const PathFigures& f = paths[0];
  ASSERT_TRUE(f.measured()) << f.skipped;
  EXPECT_TRUE(f.interrupted);
  EXPECT_EQ(f.corner_source, "sent");
  // Ticks received before 0.42 s: from the start's tick 3001 up to 4199.
  EXPECT_EQ(f.t_s.size(), static_cast<std::size_t>(4200 - 3001));
  EXPECT_EQ(f.expected_ticks, f.t_s.size());
  EXPECT_NEAR(*f.per_axis[0].rms_m, 0.5e-9, kExactM);
}

TEST(PathFigures, RefusedAndUndecidedPathsAreListedNotMeasured) {
  PathEvents events;
  LoggedPath p;
  p.version = 5;
  p.path = raster();
  p.recv_utime = at(0.1);
  events.paths.push_back(p);
  p.version = 6;
  p.recv_utime = at(0.2);
  events.paths.push_back(p);
  events.compensator.push_back(report_at(0.11, "trajectory 5 refused: axis y: exceeds its range", 0, 5));
  const std::vector<PathFigures> paths = decide_paths(events, kT0);
  ASSERT_EQ(paths.size(), 2u);
  EXPECT_EQ(paths[0].verdict, PathVerdict::kRefused);
  EXPECT_EQ(paths[0].skipped, "refused by the compensator: axis y: exceeds its range");
  EXPECT_EQ(paths[1].verdict, PathVerdict::kNone);
  EXPECT_EQ(paths[1].skipped, "no verdict of the compensator in the log");
  EXPECT_TRUE(read_windows(paths).empty());
  EXPECT_NE(path_table(paths).find("not measured: refused by the compensator: axis y: exceeds its range"),
            std::string::npos);
}

TEST_F(PathReport, TheTableGivesEachAxisItsKnownErrorAndTheMapsAreWritten) {
  const ToolRun run = report((dir_ / "xy.lcmlog").string() + " --no-plots", "table");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.err, "");

  const nlohmann::json j = read_json(dir_ / "table" / "summary.json");
  const auto& paths = j.at("scan_paths");
  ASSERT_EQ(paths.size(), 3u);
  const auto& r = paths[0];
  EXPECT_EQ(r.at("version"), kRasterVersion);
  EXPECT_EQ(r.at("path"), "raster");
  EXPECT_EQ(r.at("position"), "true");
  EXPECT_NEAR(r.at("from_s").get<double>(), kRasterStartS, 1e-12);
  EXPECT_NEAR(r.at("corner_s").get<double>(), kCornerS, 1e-12);
  EXPECT_EQ(r.at("expected_ticks"), 1600);
  EXPECT_EQ(r.at("missing_ticks"), 0);
  ASSERT_EQ(r.at("axes").size(), 2u);
  expect_axis(r.at("axes")[0], "x", 0.5e-9, 1600);
  expect_axis(r.at("axes")[1], "y", 0.8e-9, 1600);

  EXPECT_EQ(r.at("label"), "raster v77: 8 lines of 1 µm x 0.5 µm at 50 lines/s (x fast, y slow, steps, decoupled)");
  const auto& l = paths[1];
  EXPECT_EQ(l.at("path"), "lissajous");
  EXPECT_EQ(l.at("label"), "Lissajous v78: x 0.3 µm 20 Hz, y 0.2 µm 15 Hz, 0.2 s (decoupled)");
  EXPECT_NEAR(l.at("from_s").get<double>(), kLissajousStartS, 1e-12);
  expect_axis(l.at("axes")[0], "x", 0.6e-9, 2000);
  expect_axis(l.at("axes")[1], "y", 0.9e-9, 2000);

  EXPECT_EQ(paths[2].at("verdict"), "refused");
  EXPECT_FALSE(paths[2].at("measured").get<bool>());

  // raster.csv: the same figures, one row per path and axis; the refused path with why.
  const auto rows = read_csv(dir_ / "table" / "raster.csv");
  ASSERT_EQ(rows.size(), 5u);
  EXPECT_EQ(rows[1].at("axis"), "y");
  EXPECT_EQ(rows[1].at("role"), "slow");
  EXPECT_NEAR(std::stod(rows[1].at("rms_m")), 0.8e-9, 1e-18);
  EXPECT_NEAR(std::stod(rows[2].at("rms_m")), 0.6e-9, 1e-18);
  EXPECT_EQ(rows[4].at("note"), "not measured: refused by the compensator: axis x: exceeds its slew limit");

  // The printed table, and an error map per axis of the raster (none for the Lissajous figure);
  // --no-plots writes none.
  EXPECT_NE(run.out.find("| x (fast) | true | 1600 | 0.500 | 0.500 |"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("| y (slow) | true | 1600 | 0.800 | 0.800 |"), std::string::npos) << run.out;
  EXPECT_FALSE(fs::exists(dir_ / "table" / "error_map_x.dat"));
  const ToolRun maps = report((dir_ / "xy.lcmlog").string() + " --gnuplot /nonexistent/gnuplot", "maps");
  ASSERT_EQ(maps.exit_code, 0) << maps.err;
  for (const char* axis : {"x", "y"}) {
    const fs::path dat = dir_ / "maps" / (std::string("error_map_") + axis + ".dat");
    ASSERT_TRUE(fs::exists(dat)) << dat;
    // Every binned cell of y's map holds 0.8 nm (x's 0.5 nm): the map's samples are the table's.
    std::istringstream in(slurp(dat));
    std::string line;
    std::size_t cells = 0;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      double x_um = 0, y_um = 0, rms_nm = 0;
      std::istringstream fields(line);
      std::string rms_text;
      fields >> x_um >> y_um >> rms_text;
      if (rms_text == "NaN") continue;
      rms_nm = std::stod(rms_text);
      EXPECT_NEAR(rms_nm, axis[0] == 'x' ? 0.5 : 0.8, 1e-6) << line;
      ++cells;
    }
    EXPECT_GT(cells, 100u);
  }
  EXPECT_FALSE(fs::exists(dir_ / "maps" / "error_map_z.dat"));
}

TEST_F(PathReport, WithoutTheTruthTheMeasuredPositionIsUsedAndSaid) {
  write_log(dir_ / "no_truth.lcmlog", {false, 2});
  const ToolRun run = report((dir_ / "no_truth.lcmlog").string() + " --no-plots --quiet", "no_truth");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json j = read_json(dir_ / "no_truth" / "summary.json");
  const auto& r = j.at("scan_paths")[0];
  EXPECT_EQ(r.at("position"), "measured");
  expect_axis(r.at("axes")[0], "x", 3e-9, 1600);
  expect_axis(r.at("axes")[1], "y", 4e-9, 1600);
}

TEST_F(PathReport, AxisYReportsTheYTicksOfATwoAxisLog) {
  const ToolRun x = report((dir_ / "xy.lcmlog").string() + " --no-plots --csv HX_SENSOR", "axis_x");
  const ToolRun y = report((dir_ / "xy.lcmlog").string() + " --no-plots --csv HX_SENSOR --axis y", "axis_y");
  ASSERT_EQ(x.exit_code, 0) << x.err;
  ASSERT_EQ(y.exit_code, 0) << y.err;
  const nlohmann::json jx = read_json(dir_ / "axis_x" / "summary.json");
  const nlohmann::json jy = read_json(dir_ / "axis_y" / "summary.json");
  EXPECT_EQ(jx.at("axis"), "x");
  EXPECT_EQ(jy.at("axis"), "y");
  EXPECT_EQ(jy.at("tracking_samples"), kTicks);
  // y_ref - y_m of each axis: +-3 nm on x, +-4 nm on y.
  EXPECT_NEAR(jx.at("rms_error_m").get<double>(), 3e-9, kExactM);
  EXPECT_NEAR(jy.at("rms_error_m").get<double>(), 4e-9, kExactM);
  EXPECT_NEAR(jy.at("max_abs_error_m").get<double>(), 4e-9, kExactM);
  // y's parameter set is y's only.
  EXPECT_EQ(jx.at("params_history").size(), 0u);
  EXPECT_EQ(jy.at("params_history").size(), 1u);
  EXPECT_NE(y.out.find("axis                   y  (the sensor blocks carry 2 axes (x and y))"), std::string::npos)
      << y.out;
  // The CSV of the sensor channel is y's ticks.
  const auto rows = read_csv(dir_ / "axis_y" / "HX_SENSOR.csv");
  ASSERT_EQ(rows.size(), static_cast<std::size_t>(kTicks));
  for (const std::int64_t k : {std::int64_t{0}, std::int64_t{3500}, std::int64_t{7001}}) {
    EXPECT_NEAR(std::stod(rows[static_cast<std::size_t>(k)].at("y_ref_m")), reference(k)[1], 1e-15) << k;
    EXPECT_NEAR(std::stod(rows[static_cast<std::size_t>(k)].at("y_m")), reference(k)[1] - measured_error(k, 1), 1e-15)
        << k;
  }
}

TEST_F(PathReport, AnAxisTheLogLacksIsRefusedNamingTheAxesItHas) {
  const ToolRun z = report((dir_ / "xy.lcmlog").string() + " --axis z", "axis_z");
  EXPECT_EQ(z.exit_code, 2);
  EXPECT_NE(z.err.find("hystloop-report: --axis: the log's HX_SENSOR blocks carry 2 axes (x and y), not z"),
            std::string::npos)
      << z.err;
  EXPECT_FALSE(fs::exists(dir_ / "axis_z" / "summary.json"));

  write_log(dir_ / "x_only.lcmlog", {true, 1});
  const ToolRun y = report((dir_ / "x_only.lcmlog").string() + " --axis y", "x_only_y");
  EXPECT_EQ(y.exit_code, 2);
  EXPECT_NE(y.err.find("--axis: the log's HX_SENSOR blocks carry 1 axis (x), not y"), std::string::npos) << y.err;
  const ToolRun bad = report((dir_ / "xy.lcmlog").string() + " --axis w", "axis_w");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--axis"), std::string::npos) << bad.err;
}
