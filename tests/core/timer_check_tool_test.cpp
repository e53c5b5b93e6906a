// hystloop-timer-check end to end: it runs 10 kHz for a second and prints the
// figures; only their presence, accounting and order are checked (shared machine).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <regex>
#include <string>

#include "support/tool_run.hpp"

namespace {

const std::string kTool = std::string(HYSTLOOP_BINARY_DIR) + "/tools/timer-check/hystloop-timer-check";

using hystloop::testing::ToolRun;

ToolRun run_tool(const std::string& args) { return hystloop::testing::run_tool(kTool + " " + args); }

class TimerCheckTool : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(kTool)) GTEST_SKIP() << "not built: " << kTool;
  }
};

TEST_F(TimerCheckTool, Reports10kHzForOneSecond) {
  const ToolRun r = run_tool("--rate 10000 --seconds 1 --check");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex(R"(deadlines (\d+): served (\d+), skipped (\d+))")))
      << r.output;
  const long deadlines = std::stol(m[1]), served = std::stol(m[2]), skipped = std::stol(m[3]);
  EXPECT_GE(deadlines, 10'000);
  EXPECT_EQ(served + skipped, deadlines);
  ASSERT_TRUE(std::regex_search(
      r.output, m, std::regex(R"(lateness \[us\]: p50 ([\d.]+)  p99 ([\d.]+)  p99\.9 ([\d.]+)  max ([\d.]+))")))
      << r.output;
  const double p50 = std::stod(m[1]), p99 = std::stod(m[2]), p999 = std::stod(m[3]), max = std::stod(m[4]);
  EXPECT_LE(p50, p99);
  EXPECT_LE(p99, p999);
  EXPECT_LE(p999, max);
  EXPECT_NE(r.output.find("check passed"), std::string::npos) << r.output;
}

TEST_F(TimerCheckTool, HelpAndBadArguments) {
  const ToolRun help = run_tool("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.output.find("--rate"), std::string::npos) << help.output;
  EXPECT_NE(help.output.find("--seconds"), std::string::npos) << help.output;
  const ToolRun bad = run_tool("--rate 0");
  EXPECT_NE(bad.exit_code, 0) << bad.output;
  EXPECT_NE(bad.output.find("--rate"), std::string::npos) << bad.output;
}

}  // namespace
