// hystloop-report's plots, checked by what they draw: a demo-like log (a 31 s run at 10 kHz:
// safe state, the identification experiment, tracking with a linear feedforward, then with the
// MEM inverse and two parameter swaps) is written with lcm::LogFile, the tool runs on it, and
// the gnuplot script and data files it wrote are read back.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "hystloop/command_block_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/message_storage.hpp"
#include "log_test_support.hpp"
#include "models/mem.hpp"

namespace fs = std::filesystem;
using namespace hystloop;
using namespace hystloop::test;

namespace {

constexpr std::int64_t kT0 = 1'700'000'000'000'000;  // time of the first tick [us]
constexpr std::int64_t kTickUs = 100;                // 10 kHz
constexpr std::int64_t kBlock = 20;
constexpr double kDt = 1e-4;

// The run's phases [ticks]; every boundary on a block boundary.
struct Timeline {
  std::int64_t ticks = 310'000;          // 31 s
  std::int64_t armed = 5'000;            // SAFE_STATE before
  std::int64_t experiment_end = 25'000;  // experiment from `armed` to here
  std::int64_t linear_end = 65'000;      // linear feedforward from experiment_end to here, then MEM
  // The first tick commanded with v2 and with v3 (not on a second, nor on a block boundary).
  std::int64_t swap_v2 = 125'003;
  std::int64_t swap_v3 = 205'007;
};

MemParams set_of(std::int32_t version) {
  MemParams p = MemParams::paper_like();  // v1: the stage's own, as identified from the experiment
  p.c1 *= 1.0 + 0.01 * (version - 1);
  p.c2 *= 1.0 - 0.02 * (version - 1);
  p.c3 += 0.002 * (version - 1);
  return p;
}

double ref_at(std::int64_t k) { return -1.6e-6 * std::cos(2.0 * M_PI * static_cast<double>(k) * kDt); }

mem_params_t published(std::int32_t version) {
  const MemParams p = set_of(version);
  mem_params_t m{};
  m.utime = kT0;
  m.version = version;
  m.c1 = p.c1;
  m.c2 = p.c2;
  m.c3 = p.c3;
  m.residual_m = 3e-9 / version;
  m.valid = 1;
  m.source = "test";
  return m;
}

service_status_t status(const std::string& process, std::int64_t t) {
  service_status_t s{};
  s.utime = t;
  s.process = process;
  s.host = std::string(1, 'h');  // (a literal trips GCC 12's -Wrestrict once inlined)
  s.pid = 42;
  s.state = service_status_t::HEALTHY;
  s.start_utime = kT0;
  s.loop_p50_us = s.loop_p99_us = s.loop_max_us = std::nan("");
  s.latency_p50_us = s.latency_p99_us = s.latency_max_us = std::nan("");
  return s;
}

// Writes the run; the stage is the MEM model with set v1.
void write_demo_log(const fs::path& file, const Timeline& tl) {
  std::vector<Event> events;
  MemModel stage(set_of(1));
  MemInverse inverse(set_of(1));
  sensor_block_t sb{};
  command_block_t cb{};
  reserve_storage(sb);
  reserve_storage(cb);
  for (std::int64_t first = 0; first < tl.ticks; first += kBlock) {
    begin_block(cb, first, kT0 + first * kTickUs - 20'000,
                std::max<std::int64_t>(-1, first - 200 - (first / kBlock) % 7));
    begin_block(sb, first, kT0 + first * kTickUs, kDt);
    for (std::int64_t k = first; k < first + kBlock; ++k) {
      CommandTick c{k, 0.0, std::nan(""), 0, command_block_t::MODE_OFF};
      if (k >= tl.armed && k < tl.experiment_end) {
        c.mode = command_block_t::MODE_EXPERIMENT;
        c.u_ff_V = 250.0 * std::sin(20.0 * M_PI * static_cast<double>(k - tl.armed) * kDt);
      } else if (k >= tl.experiment_end && k < tl.linear_end) {
        c.mode = command_block_t::MODE_LINEAR;
        c.y_ref_m = ref_at(k);
        c.u_ff_V = c.y_ref_m / (1.25 * set_of(1).c1);  // the mean slope of its major loop
      } else if (k >= tl.linear_end) {
        c.mode = command_block_t::MODE_MEM;
        c.params_version = k < tl.swap_v2 ? 1 : (k < tl.swap_v3 ? 2 : 3);
        if (k == tl.linear_end) inverse.continue_branch(stage.branch_origin_u(), stage.input(), stage.output());
        if (k == tl.swap_v2 || k == tl.swap_v3) inverse.set_params(set_of(c.params_version));
        c.y_ref_m = ref_at(k);
        c.u_ff_V = inverse.inverse(c.y_ref_m);
      }
      append_tick(cb, c);
      SensorTick s{};
      s.u_V = c.u_ff_V;
      s.u_ff_V = c.u_ff_V;
      s.y_ref_m = c.y_ref_m;
      s.y_m = stage.forward(s.u_V);
      s.flags = sensor_block_t::SIMULATED | (k < tl.armed ? sensor_block_t::SAFE_STATE : 0);
      append_tick(sb, s);
    }
    sb.buffer_depth_ticks = 400;
    events.push_back(event(kT0 + first * kTickUs - 20'000, "HX_COMMAND", cb));
    events.push_back(event(kT0 + (first + kBlock - 1) * kTickUs, "HX_SENSOR", sb));
  }
  const auto at_tick = [](std::int64_t k) { return kT0 + k * kTickUs; };
  events.push_back(event(at_tick(tl.experiment_end) + 100'000, "HX_PARAMS", published(1)));
  events.push_back(event(at_tick(tl.swap_v2) - 2'000'000, "HX_PARAMS", published(2)));
  events.push_back(event(at_tick(tl.swap_v3) - 3'000'000, "HX_PARAMS", published(3)));
  for (std::int64_t s = 1; s * 10'000 < tl.ticks; ++s) {
    for (const char* process : {"bridge", "compensator", "logger"}) {
      events.push_back(event(at_tick(s * 10'000), "HX_STATUS", status(process, at_tick(s * 10'000))));
    }
  }
  trajectory_t traj{};
  traj.utime = at_tick(tl.experiment_end);
  traj.version = 1;
  traj.shape = trajectory_t::COSINE;
  traj.amplitude_m = 1.6e-6;
  traj.frequency_Hz = 1.0;
  events.push_back(event(at_tick(tl.experiment_end), "HX_TRAJECTORY", traj));

  write_events(file, events);
}

ToolRun run_tool(const std::string& args, const fs::path& scratch) {
  return test::run_tool(HYSTLOOP_REPORT_EXE, args, scratch);
}

// What plots.gp draws: per output file, each plot command with the title in force for it, and
// the markers set for it.
struct Panel {
  std::string title;
  std::string plot;
};
struct Figure {
  std::vector<Panel> panels;
  std::vector<double> arrow_x;
};

std::map<std::string, Figure> parse_script(const std::string& script) {
  std::map<std::string, Figure> figures;
  std::istringstream in(script);
  std::string line, output, title;
  std::vector<double> arrows;
  const std::regex set_title("^set title '(.*)'$"), set_output("^set output '(.*)'$"),
      set_arrow("^set arrow \\d+ from ([-0-9.e+]+), graph 0");
  std::smatch match;
  while (std::getline(in, line)) {
    if (std::regex_search(line, match, set_output)) {
      output = match[1];
    } else if (std::regex_search(line, match, set_title)) {
      title = match[1];
    } else if (line == "unset title") {
      title.clear();
    } else if (std::regex_search(line, match, set_arrow)) {
      arrows.push_back(std::stod(match[1]));
    } else if (line.rfind("unset arrow", 0) == 0) {
      arrows.clear();
    } else if (line.rfind("plot ", 0) == 0) {
      Figure& f = figures[output];
      f.panels.push_back({title, line});
      f.arrow_x = arrows;
    }
  }
  return figures;
}

// Rows of a whitespace-separated data file ('#' lines and blank lines skipped).
std::vector<std::vector<double>> rows_of(const fs::path& file, std::size_t* blank_lines = nullptr) {
  std::vector<std::vector<double>> rows;
  std::istringstream in(slurp(file));
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) {
      if (blank_lines != nullptr) ++*blank_lines;
      continue;
    }
    if (line[0] == '#') continue;
    std::istringstream fields(line);
    std::vector<double> row;
    std::string field;
    while (fields >> field) row.push_back(field == "NaN" ? std::nan("") : std::strtod(field.c_str(), nullptr));
    rows.push_back(row);
  }
  return rows;
}

bool have_gnuplot() { return std::system("command -v gnuplot >/dev/null 2>&1") == 0; }

double tick_t(std::int64_t k) { return static_cast<double>(k) * kDt; }

// One 31 s log and one report of it for the whole suite (writing and reporting it takes seconds).
class DemoReport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() / ("hystloop_report_plots_" + std::to_string(::getpid())));
    fs::remove_all(*dir_);
    fs::create_directories(*dir_);
    write_demo_log(*dir_ / "demo.lcmlog", Timeline{});
    run_ = new ToolRun(run_tool((*dir_ / "demo.lcmlog").string() + " --out " + (*dir_ / "out").string(), *dir_));
    std::printf("hystloop-report on a 31 s 10 kHz log (%.1f MB): %.2f s\n",
                static_cast<double>(fs::file_size(*dir_ / "demo.lcmlog")) * 1e-6, run_->seconds);
    script_ = new std::string(slurp(*dir_ / "out" / "plots.gp"));
    figures_ = new std::map<std::string, Figure>(parse_script(*script_));
  }
  static void TearDownTestSuite() {
    if (std::getenv("HYSTLOOP_KEEP_TEST_OUTPUT") == nullptr) fs::remove_all(*dir_);
    delete figures_;
    delete script_;
    delete run_;
    delete dir_;
  }
  static fs::path out(const char* name) { return *dir_ / "out" / name; }

  static fs::path* dir_;
  static ToolRun* run_;
  static std::string* script_;
  static std::map<std::string, Figure>* figures_;
};
fs::path* DemoReport::dir_ = nullptr;
ToolRun* DemoReport::run_ = nullptr;
std::string* DemoReport::script_ = nullptr;
std::map<std::string, Figure>* DemoReport::figures_ = nullptr;

TEST_F(DemoReport, RunsCleanlyAndRendersEveryPlot) {
  ASSERT_EQ(run_->exit_code, 0) << run_->err;
  EXPECT_EQ(run_->err.find("warning"), std::string::npos) << run_->err;
  if (!have_gnuplot()) GTEST_SKIP() << "no gnuplot";
  for (const char* png : {"hysteresis_u_y.png", "hysteresis_yref_y.png", "tracking_error.png", "convergence.png",
                          "run_ahead_histogram.png"}) {
    EXPECT_TRUE(is_png(out(png))) << png << "\n" << slurp(out("gnuplot.log"));
  }
  EXPECT_EQ(slurp(out("gnuplot.log")), "");  // not even a warning
}

TEST_F(DemoReport, EveryPanelCarriesItsOwnTitle) {
  const Figure& tracking = figures_->at("tracking_error.png");
  ASSERT_EQ(tracking.panels.size(), 1u);
  const std::string tracking_title = tracking.panels[0].title;
  ASSERT_FALSE(tracking_title.empty());
  const Figure& convergence = figures_->at("convergence.png");
  ASSERT_EQ(convergence.panels.size(), 4u) << *script_;
  const char* const kExpected[] = {"c1", "c2", "c3", "RMS"};
  std::set<std::string> titles;
  for (std::size_t i = 0; i < 4; ++i) {
    const Panel& p = convergence.panels[i];
    EXPECT_NE(p.title, tracking_title) << "panel " << i;
    EXPECT_EQ(p.title.rfind(kExpected[i], 0) == 0 || p.title.find(kExpected[i]) != std::string::npos, true)
        << "panel " << i << ": '" << p.title << "'";
    titles.insert(p.title);
  }
  EXPECT_EQ(titles.size(), 4u);  // none repeats another's
  for (const auto& [name, figure] : *figures_) {
    for (const auto& panel : figure.panels) EXPECT_FALSE(panel.title.empty()) << name;
  }
}

TEST_F(DemoReport, SwapMarkersAreAtTheSwapTicks) {
  const Timeline tl;
  const Figure& convergence = figures_->at("convergence.png");
  // v0 -> v1 as MEM starts, then the two swaps; each within one tick of the tick's time.
  ASSERT_EQ(convergence.arrow_x.size(), 3u) << *script_;
  const double expected[] = {tick_t(tl.linear_end), tick_t(tl.swap_v2), tick_t(tl.swap_v3)};
  for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(convergence.arrow_x[i], expected[i], 1e-4) << i;
  // No figure but convergence.png has markers.
  for (const auto& [name, figure] : *figures_) {
    if (name != "convergence.png") {
      EXPECT_TRUE(figure.arrow_x.empty()) << name;
    }
  }
}

TEST_F(DemoReport, C1C2C3AndTheHeldOutRmsAreDrawnOverTime) {
  const auto rows = rows_of(out("params.dat"));
  ASSERT_EQ(rows.size(), 3u);
  for (std::int32_t v = 1; v <= 3; ++v) {
    const auto& r = rows[static_cast<std::size_t>(v - 1)];
    ASSERT_GE(r.size(), 8u);
    EXPECT_EQ(r[1], v);
    EXPECT_NEAR(r[2], set_of(v).c1 * 1e9, 1e-6 * set_of(v).c1 * 1e9);
    EXPECT_NEAR(r[3], set_of(v).c2, 1e-6 * set_of(v).c2);
    EXPECT_NEAR(r[4], set_of(v).c3, 1e-6);
    EXPECT_NEAR(r[6], 3.0 / v, 1e-6);  // held-out RMS [nm]
  }
  const Figure& convergence = figures_->at("convergence.png");
  ASSERT_EQ(convergence.panels.size(), 4u);
  EXPECT_NE(convergence.panels[0].plot.find("$3"), std::string::npos);  // c1
  EXPECT_NE(convergence.panels[0].plot.find("$7"), std::string::npos);  // held-out RMS
  EXPECT_NE(convergence.panels[1].plot.find("$4"), std::string::npos);  // c2
  EXPECT_NE(convergence.panels[2].plot.find("$5"), std::string::npos);  // c3
}

TEST_F(DemoReport, TheLoopIsColouredByPhaseWithTheModelOnTop) {
  const Timeline tl;
  const auto experiment = rows_of(out("u_y_experiment.dat"));
  const auto tracking = rows_of(out("u_y_tracking.dat"));
  ASSERT_FALSE(experiment.empty());
  ASSERT_FALSE(tracking.empty());
  double worst_model_error = 0.0;
  for (const auto& r : experiment) {
    ASSERT_EQ(r.size(), 4u);
    EXPECT_GE(r[0], tick_t(tl.armed) - 1e-9);
    EXPECT_LT(r[0], tick_t(tl.experiment_end));
    // The identified set is the stage's: its loop is the measured one.
    ASSERT_TRUE(std::isfinite(r[3])) << r[0];
    worst_model_error = std::max(worst_model_error, std::abs(r[3] - r[2]));
  }
  EXPECT_LT(worst_model_error, 1e-3);  // [µm]
  for (const auto& r : tracking) {
    EXPECT_GE(r[0], tick_t(tl.experiment_end) - 1e-9);
    EXPECT_TRUE(std::isfinite(r[3]));
  }
  const Figure& loop = figures_->at("hysteresis_u_y.png");
  ASSERT_EQ(loop.panels.size(), 1u);
  for (const char* file : {"'u_y_experiment.dat' using 2:3", "'u_y_tracking.dat' using 2:3", "using 2:4"}) {
    EXPECT_NE(loop.panels[0].plot.find(file), std::string::npos) << file << "\n" << loop.panels[0].plot;
  }
}

TEST_F(DemoReport, Fig11ComparesTrackingWithAndWithoutCompensation) {
  const Timeline tl;
  std::size_t blank = 0;
  const auto without = rows_of(out("yref_y_without.dat"), &blank);
  const auto with = rows_of(out("yref_y_with.dat"));
  ASSERT_FALSE(without.empty());
  ASSERT_FALSE(with.empty());
  EXPECT_FALSE(fs::exists(out("yref_y_unknown.dat")));
  for (const auto& r : without) {
    EXPECT_GE(r[0], tick_t(tl.experiment_end) - 1e-9);
    EXPECT_LT(r[0], tick_t(tl.linear_end));
  }
  for (const auto& r : with) EXPECT_GE(r[0], tick_t(tl.linear_end) - 1e-9);
  // The linear feedforward leaves the hysteresis in: its y misses y_ref by far more.
  auto rms = [](const std::vector<std::vector<double>>& rows) {
    double sum = 0.0;
    for (const auto& r : rows) sum += (r[1] - r[2]) * (r[1] - r[2]);
    return std::sqrt(sum / static_cast<double>(rows.size()));
  };
  EXPECT_GT(rms(without), 5.0 * rms(with));
  const Figure& fig11 = figures_->at("hysteresis_yref_y.png");
  ASSERT_EQ(fig11.panels.size(), 1u);
  EXPECT_NE(fig11.panels[0].title.find("with and without compensation"), std::string::npos) << fig11.panels[0].title;
  EXPECT_NE(fig11.panels[0].plot.find("'yref_y_without.dat'"), std::string::npos);
  EXPECT_NE(fig11.panels[0].plot.find("'yref_y_with.dat'"), std::string::npos);
  EXPECT_NE(fig11.panels[0].plot.find("title 'without compensation (mode linear)'"), std::string::npos)
      << fig11.panels[0].plot;
  EXPECT_NE(fig11.panels[0].plot.find("title 'with compensation (mode mem)'"), std::string::npos);
}

TEST_F(DemoReport, NoUmWhereMicrometresAreMeant) {
  const std::regex um("(^|[^A-Za-z])um([^A-Za-z]|$)");
  std::string all = *script_ + run_->out + run_->err;
  for (const auto& entry : fs::directory_iterator(*dir_ / "out")) {
    if (entry.path().extension() != ".dat") continue;
    const std::string text = slurp(entry.path());
    all += text.substr(0, text.find('\n'));  // the header
  }
  std::smatch match;
  EXPECT_FALSE(std::regex_search(all, match, um)) << "'" << match.str() << "' in ...";
  EXPECT_NE(script_->find("[µm]"), std::string::npos);
}

TEST_F(DemoReport, ProgressOnStderrForALongLogAndNotWithQuiet) {
  for (const char* phase : {"reading 1 log file(s)", "computing the figures", "writing the plots' data", "done"}) {
    EXPECT_NE(run_->err.find(phase), std::string::npos) << phase << "\n" << run_->err;
  }
  const ToolRun quiet = run_tool(
      (*dir_ / "demo.lcmlog").string() + " --out " + (*dir_ / "quiet").string() + " --quiet --gnuplot /nonexistent/gp",
      *dir_);
  ASSERT_EQ(quiet.exit_code, 0) << quiet.err;
  EXPECT_EQ(quiet.err.find("hystloop-report: ["), std::string::npos) << quiet.err;
  EXPECT_NE(quiet.err.find("gnuplot not found"), std::string::npos) << quiet.err;  // warnings still come
}

TEST(ShortReport, OnlyOneKindOfTrackingIsSaidSoAndAShortLogGetsNoProgress) {
  const fs::path dir = fs::temp_directory_path() / ("hystloop_report_plots_short_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  Timeline tl;
  tl.ticks = 30'000;  // 3 s: safe state, experiment, then MEM at once
  tl.linear_end = tl.experiment_end;
  tl.swap_v2 = 27'003;
  tl.swap_v3 = 1'000'000;
  write_demo_log(dir / "short.lcmlog", tl);
  const ToolRun r = run_tool(
      (dir / "short.lcmlog").string() + " --out " + (dir / "out").string() + " --gnuplot /nonexistent/gp", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("hystloop-report: ["), std::string::npos) << r.err;
  const auto figures = parse_script(slurp(dir / "out" / "plots.gp"));
  const Figure& fig11 = figures.at("hysteresis_yref_y.png");
  ASSERT_EQ(fig11.panels.size(), 1u);
  EXPECT_NE(fig11.panels[0].title.find("only with compensation (mem) in this log"), std::string::npos)
      << fig11.panels[0].title;
  EXPECT_EQ(fig11.panels[0].plot.find("yref_y_without"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "out" / "yref_y_without.dat"));
  const Figure& convergence = figures.at("convergence.png");
  ASSERT_EQ(convergence.arrow_x.size(), 2u);
  EXPECT_NEAR(convergence.arrow_x[1], tick_t(tl.swap_v2), 1e-4);
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
}

}  // namespace
