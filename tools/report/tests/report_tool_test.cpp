// hystloop-report end to end: a log with known content is written with lcm::LogFile,
// the tool runs on it, and every figure of summary.json is checked against values
// computed here from the generator's own truth (not through report_metrics).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/model_params_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/message_storage.hpp"
#include "log_test_support.hpp"
#include <nlohmann/json.hpp>

namespace fs = std::filesystem;
using namespace hystloop;
using namespace hystloop::test;

namespace {

constexpr std::int64_t kT0 = 1'700'000'000'000'000;  // time of the first tick [us]
constexpr std::int64_t kTicks = 12'000;              // 12 s at 1 kHz (the tool does not assume 10 kHz)
constexpr std::int64_t kTickUs = 1000;
constexpr std::int64_t kBlock = 10;                     // ticks per block
constexpr std::int64_t kGapFirst = 5000, kGapLen = 10;  // ticks 5000..5009 (one block) never logged
constexpr std::int64_t kFirstReference = 1000;          // ticks before this have y_ref = NaN
constexpr std::int64_t kFirstArmed = 500;               // ticks before this carry SAFE_STATE
constexpr std::int64_t kTripFirst = 8000;               // 8000..8049: a watchdog trip
constexpr std::int64_t kDisarmFirst = 10'000;           // 10000..10049: a DISARM (not a trip)
constexpr std::int64_t kSafeLen = 50;
constexpr std::int64_t kShallowBlock = 700;  // the armed block with the lowest buffer depth
constexpr std::int64_t kResentFirst = 3990;  // a second command block for 3990..3999 (ignored)
constexpr std::int64_t kLeadUs = 20'000;     // commands are sent 20 ms ahead of their tick

bool logged(std::int64_t k) { return k < kGapFirst || k >= kGapFirst + kGapLen; }
// The tick's time on the log's clock: its block arrives as its last tick is sampled.
std::int64_t tick_utime(std::int64_t k) { return kT0 + k * kTickUs; }
// The report's time axis, by its definition: (tick time - first tick's) * 1e-6.
double tick_time(std::int64_t k) { return static_cast<double>(k * kTickUs) * 1e-6; }
double reference(std::int64_t k) {
  return k < kFirstReference ? std::nan("") : 1e-6 * std::sin(2.0 * M_PI * 0.5 * static_cast<double>(k) / 1000.0);
}
double error_of(std::int64_t k) {  // y_ref - y: larger in the first seconds, with a sign pattern
  const double size = k < 4000 ? 40e-9 : 10e-9;
  return size * static_cast<double>(1 + k % 5) * ((k % 2) != 0 ? 1.0 : -1.0);
}
bool safe(std::int64_t k) {
  return k < kFirstArmed || (k >= kTripFirst && k < kTripFirst + kSafeLen) ||
         (k >= kDisarmFirst && k < kDisarmFirst + kSafeLen);
}
bool late(std::int64_t k) { return k % 250 == 3; }
// Armed ticks the bridge clamped: to the range, by the slew limit, both at k % 1200 == 7.
bool range_clamped(std::int64_t k) { return !safe(k) && k % 400 == 7; }
bool slew_clamped(std::int64_t k) { return !safe(k) && (k % 300 == 7 || k % 300 == 8); }
std::int32_t version_in_use(std::int64_t k) { return k < 3200 ? 1 : (k < 7200 ? 2 : 4); }
// Sensor block b: ticks b * kBlock ..; its buffer depth while armed.
std::int32_t buffer_depth(std::int64_t b) { return b == kShallowBlock ? 2 : static_cast<std::int32_t>(30 + b % 17); }
bool block_armed(std::int64_t b) {
  for (std::int64_t k = b * kBlock; k < (b + 1) * kBlock; ++k) {
    if (safe(k)) return false;
  }
  return true;
}
// Command block c (ticks c * kBlock ..): the compensator had the sensor tick c * kBlock - 20 - c % 5.
std::int64_t command_sample_seq(std::int64_t c) { return std::max<std::int64_t>(-1, c * kBlock - 20 - c % 5); }
std::int64_t command_recv(std::int64_t c) { return tick_utime(c * kBlock) - kLeadUs; }
// CPU time of a process by its status number s (one a second): bridge 0.25 of a core, compensator 0.1.
std::int64_t cpu_user(const std::string& process, std::int64_t s) {
  return s * (process == "bridge" ? 200'000 : 60'000);
}
std::int64_t cpu_system(const std::string& process, std::int64_t s) {
  return s * (process == "bridge" ? 50'000 : 40'000);
}

mem_params_t params(std::int32_t version, double c1, bool valid) {
  mem_params_t p{};
  p.utime = kT0;
  p.version = version;
  p.c1 = c1;
  p.c2 = 2e-9 * version;
  p.c3 = 0.5 + 0.1 * version;
  p.residual_m = 1e-9 * version;
  p.valid = valid ? 1 : 0;
  p.source = "test";
  return p;
}

// A model change to a linear model on HX_MODEL.
model_params_t linear_model(std::int32_t version) {
  model_params_t m{};
  m.format_version = model_params_t::FORMAT_VERSION;
  m.utime = kT0;
  m.version = version;
  m.kind = model_params_t::KIND_LINEAR;
  m.linear_gain = 6.3e-9;
  m.residual_m = 4e-9;
  m.heldout_rms_m = 5e-9;
  m.valid = true;
  m.source = "test";
  return m;
}

service_status_t status(const std::string& process, std::int64_t t,
                        const std::vector<std::pair<std::string, std::int64_t>>& c) {
  service_status_t s{};
  s.utime = t;
  s.process = process;
  s.host = "h";
  s.pid = 42;
  s.state = service_status_t::HEALTHY;
  s.start_utime = kT0;
  for (auto& [name, value] : c) {
    s.counter_names.push_back(name);
    s.counter_values.push_back(value);
  }
  s.n_counters = static_cast<std::int32_t>(c.size());
  s.loop_p50_us = s.loop_p99_us = s.loop_max_us = std::nan("");
  s.latency_p50_us = s.latency_p99_us = s.latency_max_us = std::nan("");
  s.rejected = 77;
  return s;
}

struct LogOptions {
  bool logger_status = true;
  bool watchdog_counter = false;  // the bridge reports watchdog_trips = 3
};

struct LogTruth {
  std::map<std::string, std::size_t> counts;               // events per channel
  std::map<std::string, std::vector<std::int64_t>> times;  // their log times
};

// Writes the synthetic run.
LogTruth write_log(const fs::path& file, const LogOptions& o = {}) {
  std::vector<Event> events;
  sensor_block_t sb{};
  reserve_storage(sb);
  for (std::int64_t b = 0; b < kTicks / kBlock; ++b) {
    const std::int64_t first = b * kBlock;
    if (!logged(first)) continue;
    begin_block(sb, first, tick_utime(first) - 30, 1e-3);
    for (std::int64_t k = first; k < first + kBlock; ++k) {
      const double ref = reference(k);
      SensorTick t{};
      t.u_V = 10.0 * std::sin(static_cast<double>(k) / 300.0);
      t.u_ff_V = 0.9 * t.u_V;
      t.u_fb_V = 0.1 * t.u_V;
      t.y_ref_m = ref;
      t.y_m = (std::isfinite(ref) ? ref : 0.0) - error_of(k);
      t.flags = sensor_block_t::SIMULATED | (safe(k) ? sensor_block_t::SAFE_STATE : 0) |
                (late(k) ? sensor_block_t::LATE_COMMAND : 0) | (range_clamped(k) ? sensor_block_t::SATURATED : 0) |
                (slew_clamped(k) ? sensor_block_t::SLEW_LIMITED : 0);
      append_tick(sb, t);
    }
    sb.buffer_depth_ticks = block_armed(b) ? buffer_depth(b) : 0;
    events.push_back(event(tick_utime(first + kBlock - 1), "HX_SENSOR", sb));
  }
  command_block_t cb{};
  reserve_storage(cb);
  auto add_command_block = [&](std::int64_t first, std::int64_t recv, std::int64_t sample_seq, std::int32_t version) {
    begin_block(cb, first, recv - 5, sample_seq);
    for (std::int64_t k = first; k < first + kBlock; ++k) {
      append_tick(cb, {k, 1.0, reference(k), version < 0 ? version_in_use(k) : version, command_block_t::MODE_MEM});
    }
    events.push_back(event(recv, "HX_COMMAND", cb));
  };
  for (std::int64_t c = 0; c < kTicks / kBlock; ++c)
    add_command_block(c * kBlock, command_recv(c), command_sample_seq(c), -1);
  add_command_block(kResentFirst, tick_utime(kResentFirst) - 1, -1, 99);  // a re-send: the first one counts

  control_t disarm{};
  disarm.utime = tick_utime(kDisarmFirst) - 5000;
  disarm.request_id = 1;
  disarm.command = control_t::DISARM;
  disarm.target = "bridge";
  events.push_back(event(tick_utime(kDisarmFirst) - 5000, "HX_CONTROL", disarm));

  events.push_back(event(kT0 - 500'000, "HX_PARAMS", params(1, 1e-7, true)));
  events.push_back(event(kT0 + 3'000'000, "HX_PARAMS", params(2, 1.1e-7, true)));
  events.push_back(event(kT0 + 3'001'000, "HX_PARAMS", params(2, 1.1e-7, true)));  // a repeat
  events.push_back(event(kT0 + 5'000'000, "HX_PARAMS", params(3, 9e-7, false)));   // diagnostic only
  events.push_back(event(kT0 + 7'000'000, "HX_PARAMS", params(4, 1.2e-7, true)));
  events.push_back(event(kT0 + 9'000'000, "HX_MODEL", linear_model(5)));
  for (std::int64_t s = 1; s <= 12; ++s) {
    const std::int64_t t = kT0 + s * 1'000'000 - 100;
    std::vector<std::pair<std::string, std::int64_t>> bridge{{"ticks", s * 1000},
                                                             {"rejected_nonfinite", s},  // final 12
                                                             {"stale", 2},
                                                             {"command.rejected_out_of_range", 1},
                                                             {"control.rejected_decode_failed", 5},
                                                             {"cpu_user_us", cpu_user("bridge", s)},
                                                             {"cpu_system_us", cpu_system("bridge", s)}};
    if (o.watchdog_counter) bridge.emplace_back("watchdog_trips", 3);
    events.push_back(event(t, "HX_STATUS", status("bridge", t, bridge)));
    events.push_back(
        event(t + 5, "HX_STATUS",
              status("compensator", t,
                     {{"cpu_user_us", cpu_user("compensator", s)}, {"cpu_system_us", cpu_system("compensator", s)}})));
    if (o.logger_status) events.push_back(event(t + 10, "HX_STATUS", status("logger", t, {{"sensor.gaps", 1}})));
  }
  trajectory_t traj{};
  traj.utime = kT0;
  traj.version = 1;
  traj.shape = trajectory_t::SINE;
  traj.amplitude_m = 1e-6;
  traj.frequency_Hz = 0.5;
  events.push_back(event(kT0 + 900'000, "HX_TRAJECTORY", traj));

  write_events(file, events);
  LogTruth truth;
  for (const auto& e : events) {
    ++truth.counts[e.channel];
    truth.times[e.channel].push_back(e.t);
  }
  return truth;
}

ToolRun run_tool(const std::string& args, const fs::path& scratch) {
  return test::run_tool(HYSTLOOP_REPORT_EXE, args, scratch);
}

// The expected figures for ticks with lo <= t <= hi, computed from the generator's truth.
struct Expected {
  std::size_t samples = 0, tracking = 0, armed = 0, late = 0, blocks = 0;
  double rms = 0, max_abs = 0, rms_first = 0, rms_last = 0;
  double first_t = -1, last_t = -1;
  std::int32_t buffer_min = 1 << 30;
  std::int64_t trips = 0;
  std::vector<double> run_ahead;
  std::map<std::int64_t, std::pair<double, std::size_t>> bins;  // second -> (sum sq, n)
  std::size_t clamped_range = 0, clamped_slew = 0, clamped_either = 0;
  std::map<std::int64_t, std::size_t> clamped_bins;  // second -> ticks clamped by either
};

Expected expected(double lo, double hi) {
  Expected x;
  double sum = 0, first_sum = 0, last_sum = 0;
  std::size_t first_n = 0, last_n = 0;
  double t_first = -1, t_last = -1;
  std::int64_t prev = -1;
  for (std::int64_t k = 0; k < kTicks; ++k) {
    const double t = tick_time(k);
    if (!logged(k) || t < lo || t > hi) continue;
    ++x.samples;
    if (x.first_t < 0) x.first_t = t;
    x.last_t = t;
    if (!safe(k)) ++x.armed, x.late += late(k) ? 1 : 0;
    x.clamped_range += range_clamped(k) ? 1 : 0;
    x.clamped_slew += slew_clamped(k) ? 1 : 0;
    if (range_clamped(k) || slew_clamped(k)) ++x.clamped_either, ++x.clamped_bins[static_cast<std::int64_t>(t)];
    if (safe(k) && prev >= 0 && !safe(prev) && k != kDisarmFirst) ++x.trips;
    prev = k;
    if (k < kFirstReference) continue;
    if (t_first < 0) t_first = t;
    t_last = t;
  }
  for (std::int64_t k = kFirstReference; k < kTicks; ++k) {
    const double t = tick_time(k);
    if (!logged(k) || t < lo || t > hi) continue;
    const double e = error_of(k);
    ++x.tracking;
    sum += e * e;
    x.max_abs = std::max(x.max_abs, std::abs(e));
    if (t < t_first + 5.0) first_sum += e * e, ++first_n;
    if (t > t_last - 5.0) last_sum += e * e, ++last_n;
    auto& bin = x.bins[static_cast<std::int64_t>(std::floor(t))];
    bin.first += e * e, ++bin.second;
  }
  for (std::int64_t b = 0; b < kTicks / kBlock; ++b) {
    const double t = tick_time(b * kBlock + kBlock - 1);  // a block is received with its last tick
    if (!logged(b * kBlock) || t < lo || t > hi) continue;
    ++x.blocks;
    if (block_armed(b)) x.buffer_min = std::min(x.buffer_min, buffer_depth(b));
  }
  for (std::int64_t c = 0; c < kTicks / kBlock; ++c) {
    const double t = static_cast<double>(command_recv(c) - kT0) * 1e-6;
    if (command_sample_seq(c) < 0 || t < lo || t > hi) continue;
    x.run_ahead.push_back(static_cast<double>(c * kBlock - command_sample_seq(c)));
  }
  x.rms = std::sqrt(sum / static_cast<double>(x.tracking));
  x.rms_first = std::sqrt(first_sum / static_cast<double>(first_n));
  x.rms_last = std::sqrt(last_sum / static_cast<double>(last_n));
  std::sort(x.run_ahead.begin(), x.run_ahead.end());
  return x;
}

double rank(const std::vector<double>& sorted, double q) {
  const auto r = static_cast<std::size_t>(std::ceil(q * static_cast<double>(sorted.size())));
  return sorted[std::max<std::size_t>(r, 1) - 1];
}

class ReportToolTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hystloop_report_test_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    // Kept on failure, or with HYSTLOOP_KEEP_TEST_OUTPUT=1 (to look at the plots).
    if (!HasFailure() && std::getenv("HYSTLOOP_KEEP_TEST_OUTPUT") == nullptr) fs::remove_all(dir_);
  }
  fs::path dir_;
};

constexpr double kRel = 1e-9;

}  // namespace

TEST_F(ReportToolTest, EveryFigureMatchesTheGeneratedTruth) {
  const LogTruth truth = write_log(dir_ / "run.lcmlog");
  const auto& counts = truth.counts;
  const ToolRun r = run_tool((dir_ / "run.lcmlog").string() + " --out " + (dir_ / "out").string() +
                                 " --csv HX_SENSOR --csv COMMAND --csv HX_STATUS",
                             dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(slurp(dir_ / "out" / "summary.json"));
  const Expected x = expected(-1e9, 1e9);

  EXPECT_EQ(j.at("samples").get<double>(), static_cast<double>(x.samples));
  EXPECT_EQ(j.at("samples").get<double>(), static_cast<double>(kTicks - kGapLen));
  EXPECT_NEAR(j.at("duration_s").get<double>(), static_cast<double>(kTicks - 1) * 1e-3, 1e-9);
  EXPECT_EQ(j.at("tracking_samples").get<double>(), static_cast<double>(x.tracking));
  EXPECT_NEAR(j.at("rms_error_m").get<double>(), x.rms, kRel * x.rms);
  EXPECT_NEAR(j.at("max_abs_error_m").get<double>(), 200e-9, 1e-18);
  EXPECT_NEAR(j.at("max_abs_error_m").get<double>(), x.max_abs, 1e-18);
  EXPECT_NEAR(j.at("rms_error_first_5s_m").get<double>(), x.rms_first, kRel * x.rms_first);
  EXPECT_NEAR(j.at("rms_error_last_5s_m").get<double>(), x.rms_last, kRel * x.rms_last);
  EXPECT_GT(x.rms_first, 2.0 * x.rms_last);  // the generator's pattern: the test can tell them apart

  const auto& per_second = j.at("per_second");
  ASSERT_EQ(per_second.size(), 12u);
  for (std::size_t s = 0; s < per_second.size(); ++s) {
    const auto& bin = per_second[s];
    EXPECT_EQ(bin.at("t_s").get<double>(), static_cast<double>(s));
    const auto it = x.bins.find(static_cast<std::int64_t>(s));
    if (it == x.bins.end()) {
      EXPECT_TRUE(bin.at("rms_error_m").is_null()) << s;
    } else {
      const double want = std::sqrt(it->second.first / static_cast<double>(it->second.second));
      EXPECT_NEAR(bin.at("rms_error_m").get<double>(), want, kRel * want) << s;
    }
    EXPECT_EQ(bin.at("params_version").get<double>(), version_in_use(static_cast<std::int64_t>(s) * 1000 + 999)) << s;
    const auto clamped = x.clamped_bins.find(static_cast<std::int64_t>(s));
    const double want_clamped = clamped == x.clamped_bins.end() ? 0.0 : static_cast<double>(clamped->second);
    EXPECT_EQ(bin.at("clamped_ticks").get<double>(), want_clamped) << s;
    EXPECT_EQ(j.at("clamped_per_second").at(s).get<double>(), want_clamped) << s;
  }
  EXPECT_EQ(j.at("clamped_per_second").size(), per_second.size());
  const auto& clamped = j.at("clamped_ticks");
  EXPECT_EQ(clamped.at("range").get<double>(), static_cast<double>(x.clamped_range));
  EXPECT_EQ(clamped.at("slew").get<double>(), static_cast<double>(x.clamped_slew));
  EXPECT_EQ(clamped.at("either").get<double>(), static_cast<double>(x.clamped_either));
  EXPECT_LT(x.clamped_either, x.clamped_range + x.clamped_slew);  // some ticks are clamped by both

  EXPECT_EQ(j.at("armed_samples").get<double>(), static_cast<double>(x.armed));
  EXPECT_EQ(j.at("late_samples").get<double>(), static_cast<double>(x.late));
  EXPECT_NEAR(j.at("late_command_fraction").get<double>(), static_cast<double>(x.late) / static_cast<double>(x.armed),
              1e-15);

  EXPECT_EQ(j.at("late_tick_fraction").get<double>(), j.at("late_command_fraction").get<double>());
  EXPECT_GT(j.at("late_samples").get<double>(), 40.0);  // the test can tell armed from all ticks
  EXPECT_LT(j.at("late_samples").get<double>(), 48.0);

  EXPECT_EQ(j.at("tick_period_s").get<double>(), 1e-3);
  EXPECT_EQ(j.at("sensor_blocks").get<double>(), static_cast<double>(x.blocks));
  EXPECT_EQ(j.at("buffer_min_depth_ticks").get<double>(), 2.0);  // the safe blocks' 0 does not count
  EXPECT_EQ(j.at("buffer_min_depth_ticks").get<double>(), x.buffer_min);

  EXPECT_EQ(j.at("run_ahead_blocks").get<double>(), static_cast<double>(x.run_ahead.size()));
  EXPECT_EQ(j.at("run_ahead_min_ticks").get<double>(), 20.0);
  EXPECT_EQ(j.at("run_ahead_p01_ticks").get<double>(), rank(x.run_ahead, 0.01));
  EXPECT_EQ(j.at("run_ahead_p50_ticks").get<double>(), rank(x.run_ahead, 0.50));
  EXPECT_EQ(j.at("run_ahead_max_ticks").get<double>(), 24.0);

  // No watchdog_trips counter: the armed -> safe transitions, less the one DISARM explains.
  EXPECT_EQ(x.trips, 1);
  EXPECT_EQ(j.at("watchdog_trips").get<double>(), static_cast<double>(x.trips));
  EXPECT_NE(j.at("watchdog_trips_source").get<std::string>().find("transitions"), std::string::npos);

  for (const auto& [channel, times] : truth.times) {
    const double n = static_cast<double>(std::count_if(times.begin(), times.end(), [&](std::int64_t t) {
      return t >= kT0 + std::llround(x.first_t * 1e6) && t <= kT0 + std::llround(x.last_t * 1e6);
    }));
    EXPECT_NEAR(j.at("messages_per_s")[channel].get<double>(), n / (x.last_t - x.first_t), 1e-9) << channel;
  }
  EXPECT_NEAR(j.at("messages_per_s").at("HX_SENSOR").get<double>(), 100.0, 0.1);  // 1 kHz in blocks of 10
  EXPECT_NEAR(j.at("cpu_fraction").at("bridge").get<double>(), 0.25, 1e-12);
  EXPECT_NEAR(j.at("cpu_fraction").at("compensator").get<double>(), 0.1, 1e-12);
  EXPECT_TRUE(j.at("cpu_fraction").at("logger").is_null());  // it reports no CPU time

  EXPECT_EQ(j.at("commands_rejected").get<double>(), 12 + 2 + 1);  // not the control endpoint's 5, not 'rejected' (77)
  EXPECT_EQ(j.at("logger_gaps").get<double>(), 1.0);
  EXPECT_NE(j.at("logger_gaps_source").get<std::string>().find("sensor.gaps"), std::string::npos);
  EXPECT_EQ(j.at("seq_gaps").get<double>(), 1.0);
  EXPECT_EQ(j.at("missing_samples").get<double>(), static_cast<double>(kGapLen));

  const auto& history = j.at("params_history");
  ASSERT_EQ(history.size(), 5u);  // v1, v2 (its repeat folded), v3 (invalid), v4, v5 (HX_MODEL)
  const double want_t[] = {-0.5, 3.0, 5.0, 7.0};
  const int want_v[] = {1, 2, 3, 4};
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_NEAR(history[i].at("t_s").get<double>(), want_t[i], 1e-9);
    EXPECT_EQ(history[i].at("version").get<double>(), want_v[i]);
    EXPECT_EQ(history[i].at("valid").get<bool>(), want_v[i] != 3);
    EXPECT_NEAR(history[i].at("c2").get<double>(), 2e-9 * want_v[i], 1e-24);
    EXPECT_NEAR(history[i].at("residual_m").get<double>(), 1e-9 * want_v[i], 1e-24);
    EXPECT_EQ(history[i].at("model").get<std::string>(), "mem");
    EXPECT_NEAR(history[i].at("heldout_rms_m").get<double>(), 1e-9 * want_v[i], 1e-24);  // mem_params_t's residual
    EXPECT_FALSE(history[i].at("model_change").get<bool>());
  }
  const auto& change = history[4];  // a model change: kind and figures, no MEM parameters
  EXPECT_NEAR(change.at("t_s").get<double>(), 9.0, 1e-9);
  EXPECT_EQ(change.at("version").get<double>(), 5);
  EXPECT_EQ(change.at("model").get<std::string>(), "linear");
  EXPECT_TRUE(change.at("model_change").get<bool>());
  EXPECT_TRUE(change.at("c1").is_null());
  EXPECT_EQ(change.at("residual_m").get<double>(), 4e-9);
  EXPECT_EQ(change.at("heldout_rms_m").get<double>(), 5e-9);
  // rms_per_second_m: the per-second bins' RMS as a plain series.
  const auto& rms = j.at("rms_per_second_m");
  ASSERT_EQ(rms.size(), per_second.size());
  for (std::size_t s = 0; s < rms.size(); ++s) EXPECT_EQ(rms[s], per_second[s].at("rms_error_m")) << s;
  EXPECT_EQ(j.at("params_initial").at("version").get<double>(), 1);
  EXPECT_EQ(j.at("params_initial").at("c1").get<double>(), 1e-7);
  EXPECT_EQ(j.at("params_final").at("version").get<double>(), 4);
  EXPECT_EQ(j.at("params_final").at("c1").get<double>(), 1.2e-7);
  EXPECT_NEAR(j.at("params_final").at("c3").get<double>(), 0.9, 1e-15);
  EXPECT_EQ(j.at("params_updates").get<double>(), 2);  // v2 and v4; the invalid v3 is no update

  for (const auto& [channel, n] : counts)
    EXPECT_EQ(j.at("channels")[channel].get<double>(), static_cast<double>(n)) << channel;
  EXPECT_EQ(j.at("undecodable_events").get<double>(), 0);

  // CSV: header of decoded fields with units, one row per tick of the block channels.
  const std::string sensor = slurp(dir_ / "out" / "HX_SENSOR.csv");
  EXPECT_EQ(sensor.substr(0, sensor.find('\n')),
            "t_s,recv_utime_us,block_utime_us,block_seq,dt_s,buffer_depth_ticks,utime_us,seq,u_V,u_ff_V,u_fb_V,y_ref_m,"
            "y_m,flags");
  EXPECT_EQ(static_cast<std::size_t>(std::count(sensor.begin(), sensor.end(), '\n')), x.samples + 1);
  // Tick 1234 is dated on the report's axis, its block received with tick 1239.
  const std::string row_1234 =
      "1.234," + std::to_string(tick_utime(1239)) + "," + std::to_string(tick_utime(1230) - 30) + ",1230,0.001,";
  EXPECT_NE(sensor.find("\n" + row_1234), std::string::npos) << row_1234;
  const std::string command = slurp(dir_ / "out" / "HX_COMMAND.csv");
  EXPECT_EQ(command.substr(0, command.find('\n')),
            "t_s,recv_utime_us,block_utime_us,block_seq,sample_seq,seq,u_ff_V,y_ref_m,params_version,mode");
  EXPECT_EQ(static_cast<std::size_t>(std::count(command.begin(), command.end(), '\n')),
            counts.at("HX_COMMAND") * kBlock + 1);
  // A status's counters: their names in one field, their values in the next, in the same order.
  const std::string status = slurp(dir_ / "out" / "HX_STATUS.csv");
  EXPECT_NE(status.find(",n_counters,counter_names,counter_values\n"), std::string::npos) << status.substr(0, 300);
  EXPECT_NE(
      status.find(",\"ticks rejected_nonfinite stale command.rejected_out_of_range control.rejected_decode_failed "
                  "cpu_user_us cpu_system_us\",\"12000 12 2 1 5 "),
      std::string::npos);

  // Plots, when gnuplot is there; their data and script always.
  for (const char* data : {"track.dat", "per_second.dat", "run_ahead_hist.dat", "plots.gp"}) {
    EXPECT_TRUE(fs::exists(dir_ / "out" / data)) << data;
  }
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    for (const char* png :
         {"hysteresis_u_y.png", "hysteresis_yref_y.png", "tracking_error.png", "run_ahead_histogram.png"}) {
      EXPECT_TRUE(is_png(dir_ / "out" / png)) << png << "\n" << r.err;
    }
  }
  // The table.
  EXPECT_NE(r.out.find("tracking RMS error"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("run-ahead min/p1/p50"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("buffer min depth       2 ticks"), std::string::npos) << r.out;
  std::size_t worst = 0;
  for (const auto& [second, n] : x.clamped_bins) worst = std::max(worst, n);
  const std::string clamped_row = "clamped ticks          " + std::to_string(x.clamped_either) + "  (range " +
                                  std::to_string(x.clamped_range) + ", slew " + std::to_string(x.clamped_slew) +
                                  "; at most " + std::to_string(worst) + " in a second)";
  EXPECT_NE(r.out.find(clamped_row), std::string::npos) << clamped_row << "\n" << r.out;
}

TEST_F(ReportToolTest, TimeRangeAndWarmUpSelectTheSamples) {
  write_log(dir_ / "run.lcmlog", {.logger_status = false, .watchdog_counter = true});
  const ToolRun r = run_tool((dir_ / "run.lcmlog").string() + " --out " + (dir_ / "out").string() +
                                 " --from 2 --to 9 --skip-initial 1 --no-plots --quiet --csv SENSOR",
                             dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  const auto j = nlohmann::json::parse(slurp(dir_ / "out" / "summary.json"));
  const Expected x = expected(3.0, 9.0);
  EXPECT_EQ(j.at("samples").get<double>(), static_cast<double>(x.samples));
  EXPECT_NEAR(j.at("rms_error_m").get<double>(), x.rms, kRel * x.rms);
  EXPECT_NEAR(j.at("rms_error_first_5s_m").get<double>(), x.rms_first, kRel * x.rms_first);
  EXPECT_NEAR(j.at("rms_error_last_5s_m").get<double>(), x.rms_last, kRel * x.rms_last);
  EXPECT_EQ(j.at("late_samples").get<double>(), static_cast<double>(x.late));
  EXPECT_EQ(j.at("armed_samples").get<double>(), static_cast<double>(x.armed));
  EXPECT_EQ(j.at("clamped_ticks").at("either").get<double>(), static_cast<double>(x.clamped_either));
  EXPECT_EQ(j.at("clamped_ticks").at("slew").get<double>(), static_cast<double>(x.clamped_slew));
  EXPECT_EQ(j.at("sensor_blocks").get<double>(), static_cast<double>(x.blocks));
  EXPECT_EQ(j.at("run_ahead_blocks").get<double>(), static_cast<double>(x.run_ahead.size()));
  EXPECT_EQ(j.at("range").at("from_s").get<double>(), 3.0);
  EXPECT_EQ(j.at("range").at("to_s").get<double>(), 9.0);
  // Parameters in force at the start (v2), updated once (v4) inside the range.
  EXPECT_EQ(j.at("params_initial").at("version").get<double>(), 2);
  EXPECT_EQ(j.at("params_final").at("version").get<double>(), 4);
  EXPECT_EQ(j.at("params_updates").get<double>(), 1);
  // No logger status: gaps come from the sensor's seq.
  EXPECT_EQ(j.at("logger_gaps").get<double>(), 1.0);
  EXPECT_NE(j.at("logger_gaps_source").get<std::string>().find("sensor seq"), std::string::npos);
  // The bridge counts its watchdog trips: its counter is the figure.
  EXPECT_EQ(j.at("watchdog_trips").get<double>(), 3.0);
  const std::string sensor = slurp(dir_ / "out" / "HX_SENSOR.csv");
  EXPECT_EQ(static_cast<std::size_t>(std::count(sensor.begin(), sensor.end(), '\n')), x.samples + 1);
  EXPECT_FALSE(fs::exists(dir_ / "out" / "plots.gp"));
}

TEST_F(ReportToolTest, RotatedFilesReadAsOneLog) {
  write_log(dir_ / "run.lcmlog");
  // Split the log into two files at an event boundary.
  {
    lcm::LogFile in((dir_ / "run.lcmlog").string(), "r");
    lcm::LogFile a((dir_ / "run.00").string(), "w"), b((dir_ / "run.01").string(), "w");
    std::size_t n = 0;
    while (const lcm::LogEvent* e = in.readNextEvent()) {
      lcm::LogEvent copy = *e;
      (n++ < 1500 ? a : b).writeEvent(&copy);
    }
  }
  const ToolRun whole =
      run_tool((dir_ / "run.lcmlog").string() + " --out " + (dir_ / "a").string() + " --no-plots", dir_);
  const ToolRun split = run_tool(
      (dir_ / "run.00").string() + " " + (dir_ / "run.01").string() + " --out " + (dir_ / "b").string() + " --no-plots",
      dir_);
  ASSERT_EQ(whole.exit_code, 0);
  ASSERT_EQ(split.exit_code, 0) << split.err;
  const auto ja = nlohmann::json::parse(slurp(dir_ / "a" / "summary.json"));
  const auto jb = nlohmann::json::parse(slurp(dir_ / "b" / "summary.json"));
  EXPECT_EQ(ja.at("samples").get<double>(), jb.at("samples").get<double>());
  EXPECT_EQ(ja.at("rms_error_m").get<double>(), jb.at("rms_error_m").get<double>());
  EXPECT_EQ(ja.at("run_ahead_p50_ticks").get<double>(), jb.at("run_ahead_p50_ticks").get<double>());
  EXPECT_EQ(ja.at("buffer_min_depth_ticks").get<double>(), jb.at("buffer_min_depth_ticks").get<double>());
}

TEST_F(ReportToolTest, MissingGnuplotIsAWarningNotAFailure) {
  write_log(dir_ / "run.lcmlog");
  const ToolRun r = run_tool(
      (dir_ / "run.lcmlog").string() + " --out " + (dir_ / "out").string() + " --gnuplot /nonexistent/gnuplot --quiet",
      dir_);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.err.find("gnuplot not found"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "out" / "summary.json"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "plots.gp"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "track.dat"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "tracking_error.png"));
}

TEST_F(ReportToolTest, BadArgumentsExitTwoNamingTheOption) {
  write_log(dir_ / "run.lcmlog");
  const std::string log = (dir_ / "run.lcmlog").string();
  const std::string out = " --out " + (dir_ / "out").string();
  ToolRun r = run_tool(log + out + " --skip-initial -1", dir_);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--skip-initial"), std::string::npos) << r.err;
  r = run_tool(log + out + " --from 5 --to 4", dir_);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--to"), std::string::npos) << r.err;
  r = run_tool(log + out + " --csv NO_SUCH_CHANNEL", dir_);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("NO_SUCH_CHANNEL"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("HX_SENSOR"), std::string::npos) << r.err;  // lists what is there
  r = run_tool((dir_ / "missing.lcmlog").string() + out, dir_);
  EXPECT_EQ(r.exit_code, 2);
  r = run_tool(log, dir_);  // no --out
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--out"), std::string::npos) << r.err;
  r = run_tool("--help", dir_);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("--skip-initial"), std::string::npos);
}

TEST_F(ReportToolTest, CorruptEventsAreCountedNotFatal) {
  {
    lcm::LogFile log((dir_ / "bad.lcmlog").string(), "w");
    sensor_block_t s{};
    begin_block(s, 1, 0, 1e-4);
    append_tick(s, {0, 1, 0.0, 0.0, 0.0, std::nan(""), 1e-6, 0});
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(s.getEncodedSize()));
    s.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    lcm::LogEvent e{};
    e.channel = "HX_SENSOR";
    e.timestamp = kT0;
    e.datalen = static_cast<std::int32_t>(bytes.size());
    e.data = bytes.data();
    log.writeEvent(&e);
    bytes[3] ^= 0x55;  // wrong fingerprint
    e.timestamp += 100;
    log.writeEvent(&e);
    e.datalen = 5;  // truncated
    log.writeEvent(&e);
  }
  const ToolRun r =
      run_tool((dir_ / "bad.lcmlog").string() + " --out " + (dir_ / "out").string() + " --no-plots", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(slurp(dir_ / "out" / "summary.json"));
  EXPECT_EQ(j.at("samples").get<double>(), 1);
  EXPECT_EQ(j.at("undecodable_events").get<double>(), 2);
  EXPECT_TRUE(j.at("rms_error_m").is_null());
  EXPECT_TRUE(j.at("run_ahead_p50_ticks").is_null());
  EXPECT_TRUE(j.at("cpu_fraction").empty());
}

namespace {

void write_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

}  // namespace

// The probe's cases: a truncated log, a 0-byte file and random bytes all gave exit 0 and no
// word. Now every file that is not cleanly events is named in a warning, and when nothing
// decodes the tool exits 1 without writing a report.
TEST_F(ReportToolTest, DamagedLogsAreNamedAndNothingDecodableExitsOne) {
  write_log(dir_ / "run.lcmlog");
  const std::string whole = slurp(dir_ / "run.lcmlog");
  ASSERT_GT(whole.size(), 1000u);

  // Truncated mid-event: the report is still made from what is whole, with a warning.
  write_bytes(dir_ / "cut.lcmlog", whole.substr(0, whole.size() - 17));
  ToolRun r = run_tool((dir_ / "cut.lcmlog").string() + " --out " + (dir_ / "cut").string() + " --no-plots", dir_);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("cut.lcmlog: the last "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("are not a complete event (truncated log?)"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "cut" / "summary.json"));

  // Junk between two events (a torn write): lcm skips it silently; the report says so.
  const auto be32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    for (std::size_t i = 0; i < 4; ++i) v = (v << 8) | static_cast<unsigned char>(whole[at + i]);
    return v;
  };
  const std::size_t first_event = 28 + be32(20) + be32(24);
  write_bytes(dir_ / "torn.lcmlog", whole.substr(0, first_event) + std::string(13, '\x5a') + whole.substr(first_event));
  r = run_tool((dir_ / "torn.lcmlog").string() + " --out " + (dir_ / "torn").string() + " --no-plots", dir_);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("torn.lcmlog: 13 bytes between events are not events"), std::string::npos) << r.err;
  // ... and reading goes on after them (liblcm's reader stopped there, dropping the rest).
  const ToolRun clean =
      run_tool((dir_ / "run.lcmlog").string() + " --out " + (dir_ / "clean0").string() + " --no-plots", dir_);
  ASSERT_EQ(clean.exit_code, 0) << clean.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "torn" / "summary.json")).at("samples").get<double>(),
            nlohmann::json::parse(slurp(dir_ / "clean0" / "summary.json")).at("samples").get<double>());

  // A clean log: no warning at all.
  r = run_tool((dir_ / "run.lcmlog").string() + " --out " + (dir_ / "clean").string() + " --no-plots", dir_);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;

  // 0 bytes: nothing decodable, exit 1, no report.
  write_bytes(dir_ / "empty.lcmlog", "");
  r = run_tool((dir_ / "empty.lcmlog").string() + " --out " + (dir_ / "empty").string() + " --no-plots", dir_);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("empty.lcmlog: empty (0 bytes)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("nothing decodable"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "empty" / "summary.json"));

  // Random bytes (seeded; no LCM sync word in them).
  std::string noise(4096, '\0');
  std::uint64_t x = 0x9E3779B97F4A7C15ull;
  for (char& c : noise) x ^= x << 13, x ^= x >> 7, x ^= x << 17, c = static_cast<char>(x & 0x7f);
  ASSERT_EQ(noise.find("\xED\xA1\xDA\x01"), std::string::npos);
  write_bytes(dir_ / "noise.lcmlog", noise);
  r = run_tool((dir_ / "noise.lcmlog").string() + " --out " + (dir_ / "noise").string() + " --no-plots", dir_);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("noise.lcmlog: no LCM event in its 4096 bytes"), std::string::npos) << r.err;

  // An empty file among good ones: the report is made, the empty one named.
  r = run_tool((dir_ / "run.lcmlog").string() + " " + (dir_ / "empty.lcmlog").string() + " --out " +
                   (dir_ / "mixed").string() + " --no-plots",
               dir_);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("empty.lcmlog: empty (0 bytes)"), std::string::npos) << r.err;
}
