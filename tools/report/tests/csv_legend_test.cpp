// The legend files export_csv writes beside each CSV: every integer-coded column of the CSV
// named with the codes of the lcmtypes constants, the CSV itself unchanged by them.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <regex>

#include <lcm/lcm-cpp.hpp>

#include "code_legend.hpp"
#include "csv_export.hpp"
#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "log_test_support.hpp"

namespace fs = std::filesystem;
using namespace hystloop;
using namespace hystloop::report;
using namespace hystloop::test;

namespace {

constexpr std::int64_t kT0 = 1'700'000'000'000'000;  // [us]

class CsvLegendTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hystloop_csv_legend_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    lcm::LogFile log((dir_ / "run.lcmlog").string(), "w");
    ASSERT_TRUE(log.good());
    sensor_block_t s{};
    s.utime = kT0;
    s.seq = 0;
    s.dt_s = 1e-4;
    s.buffer_depth_ticks = 10;
    s.n_ticks = 2;
    s.n_axes = 1;
    s.n_values = 2;
    s.u_V = {1.0, 2.0};
    s.u_ff_V = {1.0, 2.0};
    s.u_fb_V = {0.0, 0.0};
    s.y_ref_m = {1e-6, 2e-6};
    s.y_m = {1e-6, 2e-6};
    s.flags = {0, std::int32_t{sensor_block_t::SAFE_STATE} | std::int32_t{sensor_block_t::SIMULATED}};
    write(log, kT0 + 100, "HX_SENSOR", s);
    command_block_t c{};
    c.utime = kT0;
    c.seq = 2;
    c.sample_seq = 1;
    c.n_ticks = 1;
    c.n_axes = 1;
    c.n_values = 1;
    c.u_ff_V = {3.0};
    c.y_ref_m = {3e-6};
    c.params_version = {1};
    c.mode = {command_block_t::MODE_MEM};
    write(log, kT0 + 200, "HX_COMMAND", c);
    control_t k{};
    k.utime = kT0;
    k.request_id = 7;
    k.command = control_t::SET_MODE;
    k.mode = command_block_t::MODE_LINEAR;
    write(log, kT0 + 300, "HX_CONTROL", k);
    trajectory_t t{};
    t.utime = kT0;
    t.version = 1;
    t.shape = trajectory_t::SINE;
    t.amplitude_m = 1e-6;
    t.frequency_Hz = 1.0;
    write(log, kT0 + 400, "HX_TRAJECTORY", t);
    write(log, kT0 + 500, "HX_OTHER", c);  // any type on any channel: decoded by its fingerprint
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::vector<CsvExport> run(const std::vector<std::string>& channels) {
    return export_csv({dir_ / "run.lcmlog"}, channels, kT0, -1e9, 1e9, dir_ / "out");
  }
  fs::path dir_;
};

TEST_F(CsvLegendTest, EveryCodedColumnIsNamedWithItsCodes) {
  fs::create_directories(dir_ / "out");
  const auto results = run({"HX_SENSOR", "HX_COMMAND", "HX_CONTROL", "HX_TRAJECTORY"});
  ASSERT_EQ(results.size(), 4u);
  for (const auto& r : results) {
    EXPECT_EQ(r.legend_file, dir_ / "out" / (r.channel + ".legend.txt"));
    ASSERT_TRUE(fs::exists(r.legend_file)) << r.channel;
  }
  const std::string sensor = slurp(dir_ / "out" / "HX_SENSOR.legend.txt");
  EXPECT_NE(sensor.find("HX_SENSOR.csv (hystloop.sensor_block_t)"), std::string::npos) << sensor;
  EXPECT_NE(sensor.find("\nflags: bits: 1=saturated,2=safe_state,4=simulated,8=slew_limited,16=late_command,"
                        "32=sensor_fault (0=none)\n"),
            std::string::npos)
      << sensor;

  const std::string command = slurp(dir_ / "out" / "HX_COMMAND.legend.txt");
  EXPECT_NE(command.find("\nmode: 0=off,1=linear,2=mem,3=pi,4=katalenic,5=experiment\n"), std::string::npos) << command;
  EXPECT_EQ(command.find("params_version:"), std::string::npos) << "a count is not a code: " << command;

  const std::string control = slurp(dir_ / "out" / "HX_CONTROL.legend.txt");
  EXPECT_NE(control.find("\ncommand: 1=set_mode,2=set_gains,3=arm,4=disarm,5=start_experiment,6=stop_experiment,"
                         "7=reset_counters,8=shutdown,9=set_learning,10=hold_params,11=release_params\n"),
            std::string::npos)
      << control;
  EXPECT_NE(control.find("\nmode: 0=off,1=linear,"), std::string::npos) << control;

  const std::string trajectory = slurp(dir_ / "out" / "HX_TRAJECTORY.legend.txt");
  EXPECT_NE(trajectory.find("\nshape: 0=hold,1=sine,2=cosine,3=triangle,4=points\n"), std::string::npos) << trajectory;

  // The CSV keeps its header line first and its codes as numbers: readers that skip one line still work.
  const std::string csv = slurp(dir_ / "out" / "HX_SENSOR.csv");
  EXPECT_EQ(csv.rfind("t_s,recv_utime_us,block_utime_us,", 0), 0u) << csv;
  EXPECT_NE(csv.find(",6\n"), std::string::npos) << "SAFE_STATE|SIMULATED as the number 6: " << csv;
}

TEST_F(CsvLegendTest, TheLegendFollowsTheTypeNotTheChannelName) {
  fs::create_directories(dir_ / "out");
  run({"HX_OTHER", "HX_NOTHING"});
  EXPECT_NE(slurp(dir_ / "out" / "HX_OTHER.legend.txt").find("\nmode: 0=off,"), std::string::npos);
  const std::string empty = slurp(dir_ / "out" / "HX_NOTHING.legend.txt");
  EXPECT_NE(empty.find("no column of this channel is integer-coded"), std::string::npos) << empty;
}

TEST(CodeLegend, ValuesAreTheGeneratedConstants) {
  const CodeLegend* mode = find_code_legend("hystloop.command_block_t", "mode");
  ASSERT_NE(mode, nullptr);
  ASSERT_EQ(mode->codes.size(), 6u);
  EXPECT_EQ(mode->codes[2].value, command_block_t::MODE_MEM);
  EXPECT_EQ(mode->codes[2].name, "mem");
  EXPECT_EQ(find_code_legend("hystloop.command_block_t", "seq"), nullptr);
  EXPECT_EQ(find_code_legend("hystloop.sensor_block_t", "mode"), nullptr);
  const CodeLegend* flags = find_code_legend("hystloop.sensor_block_t", "flags");
  ASSERT_NE(flags, nullptr);
  EXPECT_TRUE(flags->bits);
  for (const Code& c : flags->codes) EXPECT_EQ(c.value & (c.value - 1), 0) << c.name << " is not one bit";
  // Within one field no two codes share a value or a name.
  for (const CodeLegend& legend : code_legends()) {
    for (std::size_t i = 0; i < legend.codes.size(); ++i) {
      for (std::size_t j = i + 1; j < legend.codes.size(); ++j) {
        EXPECT_NE(legend.codes[i].value, legend.codes[j].value) << legend.type_name << "." << legend.field;
        EXPECT_NE(legend.codes[i].name, legend.codes[j].name) << legend.type_name << "." << legend.field;
      }
    }
  }
}

// A constant added to an .lcm file without a line in code_legend.cpp would leave its code
// unexplained: every integer constant of lcmtypes/ but the bounds and format numbers is in a legend.
TEST(CodeLegend, CoversEveryConstantOfTheLcmTypes) {
  const std::regex constant(R"(const\s+int\d+_t\s+(\w+)\s*=\s*(-?\d+)\s*;)");
  std::size_t seen = 0;
  for (const auto& entry : fs::directory_iterator(HYSTLOOP_LCMTYPES_DIR)) {
    if (entry.path().extension() != ".lcm") continue;
    const std::string type = "hystloop." + entry.path().stem().string();
    const std::string text = slurp(entry.path());
    for (std::sregex_iterator it(text.begin(), text.end(), constant), end; it != end; ++it) {
      const std::string name = (*it)[1];
      if (name.rfind("MAX_", 0) == 0 || name == "FORMAT_VERSION") continue;  // bounds, not codes
      ++seen;
      const std::int64_t value = std::stoll((*it)[2]);
      bool found = false;
      for (const CodeLegend& legend : code_legends()) {
        if (legend.type_name != type) continue;
        for (const Code& c : legend.codes) {
          std::string upper = c.name;
          for (char& ch : upper) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
          const bool same_name =
              name.size() >= upper.size() && name.compare(name.size() - upper.size(), upper.size(), upper) == 0;
          found = found || (same_name && c.value == value);
        }
      }
      EXPECT_TRUE(found) << type << "::" << name << " = " << value << " is in no legend (tools/report/code_legend.cpp)";
    }
  }
  EXPECT_GT(seen, 40u) << "the .lcm files were not read";
}

TEST(CsvLegendText, UnknownTypeHasNoCodes) {
  ChannelTable table;
  table.channel = "HX_X";
  Column size;
  size.name = "size_bytes";
  size.type = ColumnType::kInt64;
  table.columns.push_back(size);
  const std::string text = csv_legend_text(table);
  EXPECT_EQ(text.rfind("# Integer codes of the columns of HX_X.csv (unknown)", 0), 0u) << text;
  EXPECT_NE(text.find("no column of this channel is integer-coded"), std::string::npos);
}

}  // namespace
