// hystloop-identify on LCM logs: the reader (log_samples.hpp) on recordings written here with
// lcm::LogFile -- flagged samples skipped and counted, seq gaps counted, time from seq or
// utime, a time range, rotated files, refusals -- the message built for --publish, and the
// tool run as a process on a log (MEM recovered within 1 %). No network.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <regex>
#include <string>

#include "core/errors.hpp"
#include "log_samples.hpp"
#include "params_publish.hpp"
#include "sensor_log_fixture.hpp"
#include "support/tool_run.hpp"

namespace hystloop {
namespace {

using namespace testlog;

using testing::ToolRun;

ToolRun run_tool(const std::string& args) { return testing::run_tool(std::string(HYSTLOOP_IDENTIFY_EXE) + " " + args); }

class IdentifyLog : public ::testing::Test {
 protected:
  std::string path(const std::string& name) const { return scratch_.path(name); }
  testing::ScratchDir scratch_{"hystloop_identify_log"};
  const MemParams truth_ = MemParams::paper_like();
};

constexpr std::size_t kFlagged = kSafeCount + kFaultCount;
constexpr std::size_t kKept = kTicks - kGapCount - kFlagged;

TEST_F(IdentifyLog, SkipsFlaggedSamplesCountsTheGapAndIgnoresOtherChannels) {
  const auto record = with_faults(mem_record(truth_));
  write_log(path("run.lcmlog"), record, /*corrupt=*/true);
  const LogSamples s = read_sample_logs({path("run.lcmlog")}, {});
  EXPECT_EQ(s.files, 1u);
  EXPECT_EQ(s.sensor_events, blocks_written(record, 0, record.size()) + 2);
  EXPECT_EQ(s.sensor_ticks, record.size());
  EXPECT_EQ(s.safe_state, kSafeCount);
  EXPECT_EQ(s.sensor_fault, kFaultCount);
  EXPECT_EQ(s.undecodable, 2u);  // a mem_params_t and a truncated block on HX_SENSOR
  EXPECT_EQ(s.duplicates, 0u);
  EXPECT_EQ(s.gaps, 1u);
  EXPECT_EQ(s.missing, kGapCount);
  ASSERT_EQ(s.first_gaps.size(), 1u);
  EXPECT_EQ(s.first_gaps[0].first_missing, kFirstSeq + static_cast<std::int64_t>(kGapBegin));
  ASSERT_EQ(s.table.t.size(), kKept);
  EXPECT_EQ(s.first_seq, kFirstSeq);
  EXPECT_EQ(s.last_seq, kFirstSeq + static_cast<std::int64_t>(kTicks) - 1);
  // t = (seq - first seq) * dt: the sample after the gap sits where its tick was.
  EXPECT_DOUBLE_EQ(s.table.t.front(), 0.0);
  EXPECT_NEAR(s.table.t.back(), static_cast<double>(kTicks - 1) * 1e-4, 1e-12);
  const std::size_t after_gap = kGapBegin - kFlagged;  // index in the table of the first sample after the gap
  EXPECT_NEAR(s.table.t[after_gap], static_cast<double>(kGapBegin + kGapCount) * 1e-4, 1e-12);
  EXPECT_NEAR(s.window_s(), 1.9999, 1e-12);
  // Nothing flagged or from another rig got in.
  for (std::size_t i = 0; i < s.table.y.size(); ++i) ASSERT_LT(std::abs(s.table.y[i]), 5e-6) << i;
  const std::string text = describe(s, {});
  EXPECT_NE(text.find("10 SAFE_STATE, 3 SENSOR_FAULT"), std::string::npos) << text;
  EXPECT_NE(text.find("seq gaps: 1 (50 samples missing); seq 13000 +50"), std::string::npos) << text;
}

// A stage of two axes: every block carries x and y. x is the record, y the same stage twice as
// stiff (half the travel); --axis chooses, and an axis the blocks do not carry is refused.
void write_two_axis_log(const std::string& file, const std::vector<SensorTick>& x) {
  lcm::LogFile log(file, "w");
  ASSERT_TRUE(log.good()) << file;
  std::int64_t eventnum = 0;
  for (const auto& [first, last] : block_ranges(x, 0, x.size())) {
    sensor_block_t b{};
    begin_block(b, x[first].seq, x[first].utime, 1e-4, 2);
    for (std::size_t i = first; i < last; ++i) {
      SensorTick y = x[i];
      y.y_m = 0.5 * x[i].y_m;
      const std::array<SensorTick, 2> both{x[i], y};
      ASSERT_TRUE(append_tick(b, both));
    }
    write_event(log, eventnum, x[last - 1].utime, "HX_SENSOR", encoded(b));
  }
}

TEST_F(IdentifyLog, TheAxisOfAStageOfSeveralIsChosenAndOneTheBlocksLackIsRefused) {
  const auto record = mem_record(truth_);
  write_two_axis_log(path("xy.lcmlog"), record);
  const LogSamples x = read_sample_logs({path("xy.lcmlog")}, {});
  LogReadOptions on_y;
  on_y.axis = 1;
  const LogSamples y = read_sample_logs({path("xy.lcmlog")}, on_y);
  ASSERT_EQ(x.table.y.size(), record.size());
  ASSERT_EQ(y.table.y.size(), record.size());
  for (std::size_t i = 0; i < record.size(); i += 997) {
    EXPECT_EQ(x.table.y[i], record[i].y_m) << i;
    EXPECT_EQ(y.table.y[i], 0.5 * record[i].y_m) << i;
    EXPECT_EQ(y.table.u[i], record[i].u_V) << i;
  }
  LogReadOptions on_z;
  on_z.axis = 2;
  try {
    read_sample_logs({path("xy.lcmlog")}, on_z);
    FAIL() << "z read from blocks of x and y";
  } catch (const SampleLogError& e) {
    EXPECT_NE(std::string(e.what()).find("its blocks carry 2 axes (x and y), not z (--axis)"), std::string::npos)
        << e.what();
  }
  // The tool: y's linear gain is half x's; z is refused; an axis that is no axis is a usage error.
  const ToolRun gx = run_tool(path("xy.lcmlog") + " --model linear --out " + path("x.yaml"));
  const ToolRun gy = run_tool(path("xy.lcmlog") + " --model linear --axis y --out " + path("y.yaml"));
  ASSERT_EQ(gx.exit_code, 0) << gx.output;
  ASSERT_EQ(gy.exit_code, 0) << gy.output;
  const double gain_x = YAML::LoadFile(path("x.yaml"))["linear"]["gain"].as<double>();
  const double gain_y = YAML::LoadFile(path("y.yaml"))["linear"]["gain"].as<double>();
  EXPECT_NEAR(gain_y / gain_x, 0.5, 1e-9);
  const ToolRun gz = run_tool(path("xy.lcmlog") + " --model linear --axis z --out " + path("z.yaml"));
  EXPECT_EQ(gz.exit_code, 2) << gz.output;
  EXPECT_NE(gz.output.find("not z (--axis)"), std::string::npos) << gz.output;
  EXPECT_EQ(run_tool(path("xy.lcmlog") + " --model linear --axis w").exit_code, 2);
}

TEST_F(IdentifyLog, TimeFromUtimeAndAnotherRig) {
  auto record = with_faults(mem_record(truth_));
  for (auto& r : record) r.utime += (r.seq - kFirstSeq) * 100;  // a 5 kHz clock in utime: 200 us per tick
  write_log(path("run.lcmlog"), record, 0, record.size(), false, "HX_SENSOR", 2e-4);
  LogReadOptions o;
  o.time_base = LogTimeBase::utime;
  const LogSamples s = read_sample_logs({path("run.lcmlog")}, o);
  EXPECT_NEAR(s.table.t.back(), static_cast<double>(kTicks - 1) * 2e-4, 1e-9);
  // RIG2_SENSOR holds a copy of every 1000th tick (two of them flagged), its own y.
  o = {};
  o.sensor_channel = "RIG2_SENSOR";
  const LogSamples other = read_sample_logs({path("run.lcmlog")}, o);
  EXPECT_EQ(other.sensor_events, 20u);
  EXPECT_EQ(other.safe_state + other.sensor_fault, 2u);
  ASSERT_EQ(other.table.t.size(), 18u);
  for (const double y : other.table.y) EXPECT_EQ(y, 5e-6);
  EXPECT_EQ(other.gaps, 19u);
  EXPECT_EQ(other.missing, static_cast<std::size_t>(*other.last_seq - *other.first_seq + 1) - 20u);
}

TEST_F(IdentifyLog, TimeRangeIsRelativeToTheFirstSampleAndHalfOpen) {
  write_log(path("run.lcmlog"), with_faults(mem_record(truth_)));
  LogReadOptions o;
  o.from_s = 0.5;
  o.to_s = 1.5;
  const LogSamples s = read_sample_logs({path("run.lcmlog")}, o);
  // [0.5, 1.5) holds 10000 ticks, all the planted faults among them.
  EXPECT_EQ(s.table.t.size(), 10'000u - kGapCount - kFlagged);
  EXPECT_EQ(s.outside_range, kTicks - 10'000u);
  EXPECT_EQ(s.gaps, 1u);
  EXPECT_NEAR(s.table.t.front(), 0.501, 1e-12);  // the first 10 ticks from 0.5 s are SAFE_STATE
  EXPECT_NEAR(s.table.t.back(), 1.4999, 1e-12);
  // A range that starts right after the gap sees no gap (entering the range is not one).
  o.from_s = static_cast<double>(kGapBegin + kGapCount) * 1e-4;
  o.to_s.reset();
  const LogSamples late = read_sample_logs({path("run.lcmlog")}, o);
  EXPECT_EQ(late.gaps, 0u);
  EXPECT_EQ(late.table.t.size(), kTicks - kGapBegin - kGapCount);
  // Nothing in range: refused, with the counts.
  o.from_s = 5.0;
  try {
    read_sample_logs({path("run.lcmlog")}, o);
    FAIL() << "an empty range was accepted";
  } catch (const SampleLogError& e) {
    EXPECT_NE(std::string(e.what()).find("no usable HX_SENSOR sample"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("19950 outside the time range"), std::string::npos) << e.what();
  }
}

TEST_F(IdentifyLog, RotatedFilesAreOneRecordInTheOrderGiven) {
  const auto record = with_faults(mem_record(truth_));
  const std::size_t cut = 9'000;  // between the planted faults, before the gap
  write_log(path("run.000.lcmlog"), record, 0, cut);
  write_log(path("run.001.lcmlog"), record, cut, record.size());
  const LogSamples s = read_sample_logs({path("run.000.lcmlog"), path("run.001.lcmlog")}, {});
  EXPECT_EQ(s.files, 2u);
  EXPECT_EQ(s.table.t.size(), kKept);
  EXPECT_EQ(s.gaps, 1u);  // only the planted one: the file boundary is not a gap
  EXPECT_EQ(s.missing, kGapCount);
  try {
    read_sample_logs({path("run.001.lcmlog"), path("run.000.lcmlog")}, {});
    FAIL() << "files out of order were accepted";
  } catch (const SampleLogError& e) {
    EXPECT_NE(std::string(e.what()).find("run.000.lcmlog: event 0: seq goes back"), std::string::npos) << e.what();
  }
  // The same file twice: every sample of the second copy is a repeat or goes back -> refused.
  EXPECT_THROW(read_sample_logs({path("run.001.lcmlog"), path("run.001.lcmlog")}, {}), SampleLogError);
}

TEST_F(IdentifyLog, RepeatedTicksAreSkippedAndCounted) {
  auto record = mem_record(truth_);
  record.insert(record.begin() + 300, record[299]);  // the next block starts with tick 299 again
  write_log(path("run.lcmlog"), record);
  const LogSamples s = read_sample_logs({path("run.lcmlog")}, {});
  EXPECT_EQ(s.duplicates, 1u);
  EXPECT_EQ(s.table.t.size(), kTicks);
  EXPECT_EQ(s.gaps, 0u);
  // A whole block logged twice.
  record = mem_record(truth_);
  {
    lcm::LogFile log(path("twice.lcmlog"), "w");
    std::int64_t eventnum = 0;
    for (const auto& [first, last] : block_ranges(record, 0, 100)) {
      const auto bytes = encoded(make_block(record, first, last));
      write_event(log, eventnum, record[last - 1].utime, "HX_SENSOR", bytes);
      if (first == 50) write_event(log, eventnum, record[last - 1].utime, "HX_SENSOR", bytes);
    }
  }
  const LogSamples twice = read_sample_logs({path("twice.lcmlog")}, {});
  EXPECT_EQ(twice.duplicates, kBlockTicks);
  EXPECT_EQ(twice.table.t.size(), 100u);
}

TEST_F(IdentifyLog, NonFiniteValueIsRefusedNamingFileEventAndSeq) {
  for (const bool in_u : {false, true}) {
    auto record = mem_record(truth_);
    (in_u ? record[1234].u_V : record[1234].y_m) =
        in_u ? std::numeric_limits<double>::infinity() : std::numeric_limits<double>::quiet_NaN();
    write_log(path("nan.lcmlog"), record);
    try {
      read_sample_logs({path("nan.lcmlog")}, {});
      FAIL() << "a non-finite sample was accepted";
    } catch (const SampleLogError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("nan.lcmlog: event "), std::string::npos) << what;
      EXPECT_NE(what.find("(seq 2234): " + std::string(in_u ? "u_V" : "y_m") + " is not finite"), std::string::npos)
          << what;
    }
  }
}

TEST_F(IdentifyLog, OptionsAndFilesAreChecked) {
  LogReadOptions o;
  o.dt_s = 0.0;
  EXPECT_THROW(o.validate(), ParameterError);
  o = {};
  o.from_s = 1.0;
  o.to_s = 1.0;
  try {
    o.validate();
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "to");
  }
  o = {};
  o.from_s = -1.0;
  EXPECT_THROW(o.validate(), ParameterError);
  EXPECT_THROW(read_sample_logs({path("missing.lcmlog")}, {}), SampleLogError);
  {
    std::FILE* f = std::fopen(path("text.lcmlog").c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("t,u,y\n0,0,0\n", f);
    std::fclose(f);
  }
  EXPECT_THROW(read_sample_logs({path("text.lcmlog")}, {}), SampleLogError);  // no event: nothing usable
  EXPECT_TRUE(looks_like_lcm_log("/x/hystloop-20240101-120000.003.lcmlog"));
  EXPECT_FALSE(looks_like_lcm_log("/x/data.csv"));
  EXPECT_FALSE(looks_like_lcm_log("/x/lcmlog-2024-01-01.00"));
}

TEST(IdentifyPublish, VersionAndMessage) {
  EXPECT_EQ(next_params_version(0), 2);  // nothing heard: above a compensator's configured version 1
  EXPECT_EQ(next_params_version(1), 2);
  EXPECT_EQ(next_params_version(7), 8);
  EXPECT_EQ(next_params_version(std::numeric_limits<std::int32_t>::max()), std::numeric_limits<std::int32_t>::max());
  MemFitResult fit;
  fit.params = {4e-9, 2e-12, 1.1};
  fit.status = FitStatus::ok;
  fit.residual_rms_m = 1.5e-9;
  fit.samples_used = 1234;
  const mem_params_t m = to_mem_params(fit, 1.9999, 9, 42, "hystloop-identify@h");
  EXPECT_EQ(m.version, 9);
  EXPECT_EQ(m.utime, 42);
  EXPECT_EQ(m.c1, 4e-9);
  EXPECT_EQ(m.c2, 2e-12);
  EXPECT_EQ(m.c3, 1.1);
  EXPECT_EQ(m.residual_m, 1.5e-9);
  EXPECT_EQ(m.samples_used, 1234);
  EXPECT_EQ(m.window_s, 1.9999);
  EXPECT_TRUE(m.valid);
  EXPECT_EQ(m.source, "hystloop-identify@h");
  EXPECT_EQ(identify_source().rfind("hystloop-identify@", 0), 0u);
  PublishOptions p;
  p.version = 0;
  EXPECT_THROW(p.validate(), ParameterError);
  p = {};
  p.rig = "hx";
  EXPECT_THROW(p.validate(), ParameterError);
  p = {};
  p.listen_s = -1.0;
  EXPECT_THROW(p.validate(), ParameterError);
  // A URL whose packets could leave the host is refused before LCM starts.
  p = {};
  p.lcm_url = "udpm://239.255.76.67:7667?ttl=1";
  EXPECT_THROW(ParamsLink link(p), ParameterError);
}

// --- the tool as a process ----------------------------------------------------------------

double yaml_value(const std::string& file, const char* key) { return YAML::LoadFile(file)["mem"][key].as<double>(); }

std::size_t fit_samples(const std::string& output) {
  std::smatch m;
  if (!std::regex_search(output, m, std::regex(R"(RMS, (\d+) samples, )"))) return 0;
  return std::stoul(m[1].str());
}

// The fit's residual [nm] as printed. The robust fit keeps c1..c3 within 1 % even with the
// flagged samples' junk in the data; the residual (~500 nm then) is what shows it.
double fit_residual_nm(const std::string& output) {
  std::smatch m;
  if (!std::regex_search(output, m, std::regex(R"(fit: residual ([-+0-9.eE]+) nm RMS)"))) return -1.0;
  return std::stod(m[1].str());
}

TEST_F(IdentifyLog, ToolRecoversMemFromRotatedLogsAndReportsSkipsAndTheGap) {
  const auto record = with_faults(mem_record(truth_, 0.5e-9));
  write_log(path("run.000.lcmlog"), record, 0, 9'000, /*corrupt=*/true);
  write_log(path("run.001.lcmlog"), record, 9'000, record.size());
  const ToolRun r =
      run_tool(path("run.000.lcmlog") + " " + path("run.001.lcmlog") + " --model mem --out " + path("p.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("log: 2 file(s)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("samples: " + std::to_string(kKept) + " kept"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("skipped: 10 SAFE_STATE, 3 SENSOR_FAULT, 0 repeated seq, 2 block(s) undecodable"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("seq gaps: 1 (50 samples missing)"), std::string::npos) << r.output;
  EXPECT_GT(fit_residual_nm(r.output), 0.0) << r.output;
  EXPECT_LT(fit_residual_nm(r.output), 1.0) << r.output;  // 0.5 nm noise
  EXPECT_NEAR(yaml_value(path("p.yaml"), "c1"), truth_.c1, 0.01 * truth_.c1) << r.output;
  EXPECT_NEAR(yaml_value(path("p.yaml"), "c2"), truth_.c2, 0.01 * truth_.c2) << r.output;
  EXPECT_NEAR(yaml_value(path("p.yaml"), "c3"), truth_.c3, 0.01 * truth_.c3) << r.output;
}

TEST_F(IdentifyLog, ToolFitsOnlyTheTimeRange) {
  write_log(path("run.lcmlog"), with_faults(mem_record(truth_, 0.5e-9)));
  const ToolRun all = run_tool(path("run.lcmlog") + " --model mem");
  ASSERT_EQ(all.exit_code, 0) << all.output;
  const ToolRun part = run_tool(path("run.lcmlog") + " --model mem --from 0.5 --to 1.5 --out " + path("p.yaml"));
  ASSERT_EQ(part.exit_code, 0) << part.output;
  EXPECT_LT(fit_residual_nm(part.output), 1.0) << part.output;
  const std::size_t in_range = 10'000u - kGapCount - kFlagged;
  EXPECT_NE(part.output.find("samples: " + std::to_string(in_range) + " kept"), std::string::npos) << part.output;
  EXPECT_NE(part.output.find(", 10000 outside the time range"), std::string::npos) << part.output;
  // The fit uses the samples on branches, after the first reversal (t = 0.525 s): a quarter
  // period fewer than the range holds, and about half of what the whole record gives.
  const std::size_t used = fit_samples(part.output), used_all = fit_samples(all.output);
  EXPECT_LE(used, in_range) << part.output;
  EXPECT_GE(used, in_range - 260) << part.output;
  EXPECT_NEAR(static_cast<double>(used) / static_cast<double>(used_all), 0.5, 0.02) << all.output;
  EXPECT_NEAR(yaml_value(path("p.yaml"), "c1"), truth_.c1, 0.01 * truth_.c1) << part.output;
  EXPECT_NEAR(yaml_value(path("p.yaml"), "c3"), truth_.c3, 0.01 * truth_.c3) << part.output;
}

// The memory bound on a log: a record above --max-samples is refused before any fit, with
// --from/--to and --decimate as the ways out; a range under the bound fits.
TEST_F(IdentifyLog, ToolRefusesMoreSamplesThanTheBoundAndARangeFits) {
  write_log(path("run.lcmlog"), with_faults(mem_record(truth_, 0.5e-9)));
  const ToolRun big = run_tool(path("run.lcmlog") + " --model mem --max-samples 15000");
  EXPECT_EQ(big.exit_code, 2) << big.output;
  EXPECT_NE(big.output.find("exceed --max-samples 15000"), std::string::npos) << big.output;
  EXPECT_NE(big.output.find("--from/--to"), std::string::npos) << big.output;
  EXPECT_EQ(big.output.find("mem: c1 "), std::string::npos) << big.output;
  const ToolRun part = run_tool(path("run.lcmlog") + " --model mem --max-samples 15000 --from 0.5 --to 1.5");
  EXPECT_EQ(part.exit_code, 0) << part.output;
  // A folder where a log was expected: a usage error, not CLI11's 105.
  const ToolRun dir = run_tool(path("") + " --log --model mem");
  EXPECT_EQ(dir.exit_code, 2) << dir.output;
}

TEST_F(IdentifyLog, ToolReadsAnyNameWithLogAndRefusesBadInput) {
  const auto record = mem_record(truth_);
  write_log(path("lcmlog-2024-01-01.00"), record);
  const ToolRun r = run_tool(path("lcmlog-2024-01-01.00") + " --log --model mem");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("samples: 20000 kept"), std::string::npos) << r.output;
  // Without --log the file is read as CSV and refused.
  EXPECT_EQ(run_tool(path("lcmlog-2024-01-01.00") + " --model mem").exit_code, 2);
  // Another rig's prefix: its channel is not in this log.
  const ToolRun rig = run_tool(path("lcmlog-2024-01-01.00") + " --log --rig RIG3_ --model mem");
  EXPECT_EQ(rig.exit_code, 2) << rig.output;
  EXPECT_NE(rig.output.find("no usable RIG3_SENSOR sample"), std::string::npos) << rig.output;
  EXPECT_EQ(run_tool(path("lcmlog-2024-01-01.00") + " --log --rig hx --model mem").exit_code, 2);
  // A non-finite value: exit 2 naming where.
  auto bad = record;
  bad[77].y_m = std::numeric_limits<double>::quiet_NaN();
  write_log(path("nan.lcmlog"), bad);
  const ToolRun n = run_tool(path("nan.lcmlog") + " --model mem");
  EXPECT_EQ(n.exit_code, 2) << n.output;
  EXPECT_NE(n.output.find("nan.lcmlog: event"), std::string::npos) << n.output;
  EXPECT_NE(n.output.find("y_m is not finite"), std::string::npos) << n.output;
  // Mixed inputs, a range on a CSV, a bad range.
  {
    std::FILE* f = std::fopen(path("d.csv").c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("t,u,y\n0,0,0\n", f);
    std::fclose(f);
  }
  const ToolRun mixed = run_tool(path("d.csv") + " " + path("nan.lcmlog") + " --model banning");
  EXPECT_EQ(mixed.exit_code, 2) << mixed.output;
  EXPECT_NE(mixed.output.find("mixed inputs"), std::string::npos) << mixed.output;
  EXPECT_EQ(run_tool(path("d.csv") + " --model mem --from 1").exit_code, 2);
  const ToolRun range = run_tool(path("lcmlog-2024-01-01.00") + " --log --model mem --from 1 --to 0.5");
  EXPECT_EQ(range.exit_code, 2) << range.output;
  EXPECT_NE(range.output.find("to: must be > from"), std::string::npos) << range.output;
}

// What cannot be published is refused before any LCM is opened (publishing itself, on HX_MODEL
// and HX_PARAMS, and the adoption: identify_publish_test.cpp, inside a private namespace).
TEST_F(IdentifyLog, ToolRefusesWhatCannotBePublished) {
  write_log(path("run.lcmlog"), mem_record(truth_));
  const ToolRun pi = run_tool(path("run.lcmlog") + " --model pi --publish --publish-on params");
  EXPECT_EQ(pi.exit_code, 2) << pi.output;
  EXPECT_NE(pi.output.find("--publish-on params sends MEM parameters"), std::string::npos) << pi.output;
  EXPECT_NE(pi.output.find("only with --model mem"), std::string::npos) << pi.output;
  const ToolRun banning = run_tool(path("run.lcmlog") + " --model banning --publish");
  EXPECT_EQ(banning.exit_code, 2) << banning.output;
  EXPECT_NE(banning.output.find("Banning's model is identified offline only"), std::string::npos) << banning.output;
  for (const char* alone : {"--no-wait", "--timeout 2", "--publish-on model"}) {
    const ToolRun r = run_tool(path("run.lcmlog") + " --model mem " + alone);
    EXPECT_EQ(r.exit_code, 2) << alone << ": " << r.output;
    EXPECT_NE(r.output.find("only with --publish"), std::string::npos) << alone << ": " << r.output;
  }
  const ToolRun both = run_tool(path("run.lcmlog") + " --model mem --publish --timeout 2 --no-wait");
  EXPECT_EQ(both.exit_code, 2) << both.output;
  EXPECT_NE(both.output.find("choose one"), std::string::npos) << both.output;
}

}  // namespace
}  // namespace hystloop
