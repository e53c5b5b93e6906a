// The replay tools' exit codes on failures, as tools/replay-check reads them: replay-compare exits
// 1 only for a verdict on the compensator, so a log it cannot use exits 2 (naming the argument);
// replay-filter exits 1 for a log it cannot read and 2 for a refused command line.

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "support/tool_run.hpp"

namespace {

using hystloop::testing::run_tool;
using hystloop::testing::ScratchDir;
using hystloop::testing::ToolRun;

const std::string kCompare = HYSTLOOP_REPLAY_COMPARE_EXE;
const std::string kFilter = HYSTLOOP_REPLAY_FILTER_EXE;

TEST(ReplayCompareExit, AMissingLogIsRefusedNamingTheArgumentNotADivergence) {
  ScratchDir dir("replay_compare_exit");
  const ToolRun r = run_tool(kCompare + " " + dir.path("missing.lcmlog") + " " + dir.path("also-missing.lcmlog"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("hystloop-replay-compare: expected: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("no such log file"), std::string::npos) << r.output;
}

TEST(ReplayCompareExit, ALogWithoutCommandsIsRefusedNamingTheArgument) {
  ScratchDir dir("replay_compare_exit");
  std::ofstream(dir.path("empty.lcmlog")).flush();
  const ToolRun r = run_tool(kCompare + " " + dir.path("empty.lcmlog") + " " + dir.path("empty.lcmlog"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("expected: " + dir.path("empty.lcmlog") + " holds no HX_COMMAND command"), std::string::npos)
      << r.output;
}

TEST(ReplayFilterExit, AnUnreadableLogIsARuntimeFailure) {
  ScratchDir dir("replay_filter_exit");
  const ToolRun r = run_tool(kFilter + " inputs " + dir.path("missing.lcmlog") + " " + dir.path("out.lcmlog"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("hystloop-replay-filter: " + dir.path("missing.lcmlog") + ": no such log file"),
            std::string::npos)
      << r.output;
}

TEST(ReplayFilterExit, AlterWithoutATickIsRefusedNamingTheOption) {
  ScratchDir dir("replay_filter_exit");
  const ToolRun r = run_tool(kFilter + " alter " + dir.path("missing.lcmlog") + " " + dir.path("out.lcmlog"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("hystloop-replay-filter: --seq: "), std::string::npos) << r.output;
}

}  // namespace
