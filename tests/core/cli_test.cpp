// The command-line contract (core/cli.hpp): parse errors exit 2 with "<program>: <message>", and
// a word where a required command was expected is named as an unknown command, with the commands
// there are (CLI11 alone says "A subcommand is required").
#include "core/cli.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace hystloop {
namespace {

struct Parsed {
  std::optional<int> exit_code;
  std::string err;
};

Parsed parse(CLI::App& app, std::vector<const char*> argv) {
  testing::internal::CaptureStderr();
  Parsed p;
  p.exit_code = parse_cli(app, static_cast<int>(argv.size()), argv.data());
  p.err = testing::internal::GetCapturedStderr();
  return p;
}

TEST(ParseCli, AnUnknownCommandIsNamedWithTheCommandsThereAre) {
  CLI::App app{"tool"};
  app.require_subcommand(1);
  app.add_subcommand("arm", "");
  app.add_subcommand("status", "");
  const Parsed p = parse(app, {"/usr/bin/hystloop-ctl", "bogus"});
  ASSERT_EQ(p.exit_code, kExitUsage);
  EXPECT_EQ(p.err.rfind("hystloop-ctl: unknown command 'bogus' (one of: arm, status)\n", 0), 0u) << p.err;
}

TEST(ParseCli, OtherErrorsKeepCli11sMessageAndNoCommandIsNotAnUnknownOne) {
  CLI::App app{"tool"};
  app.require_subcommand(1);
  app.add_subcommand("arm", "");
  Parsed p = parse(app, {"hystloop-ctl"});
  EXPECT_EQ(p.exit_code, kExitUsage);
  EXPECT_NE(p.err.find("A subcommand is required"), std::string::npos) << p.err;
  p = parse(app, {"hystloop-ctl", "arm", "--bogus"});
  EXPECT_EQ(p.exit_code, kExitUsage);
  EXPECT_NE(p.err.find("--bogus"), std::string::npos) << p.err;
  EXPECT_EQ(p.err.find("unknown command"), std::string::npos) << p.err;
  CLI::App app2{"tool"};
  app2.add_subcommand("arm", "")->callback([] {});
  EXPECT_EQ(parse(app2, {"hystloop-ctl", "arm"}).exit_code, std::nullopt);
}

}  // namespace
}  // namespace hystloop
