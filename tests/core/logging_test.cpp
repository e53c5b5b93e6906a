#include "core/logging.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "core/errors.hpp"

namespace hystloop {
namespace {

std::filesystem::path temp_path(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("hystloop_logging_test_" + std::to_string(::getpid()) + "_" + name);
}

std::string read_all(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(Logging, ParsesEveryLevelCaseInsensitively) {
  using spdlog::level::level_enum;
  EXPECT_EQ(parse_log_level("trace"), level_enum::trace);
  EXPECT_EQ(parse_log_level("DEBUG"), level_enum::debug);
  EXPECT_EQ(parse_log_level("Info"), level_enum::info);
  EXPECT_EQ(parse_log_level("warn"), level_enum::warn);
  EXPECT_EQ(parse_log_level("warning"), level_enum::warn);
  EXPECT_EQ(parse_log_level("error"), level_enum::err);
  EXPECT_EQ(parse_log_level("critical"), level_enum::critical);
  EXPECT_EQ(parse_log_level("off"), level_enum::off);
}

TEST(Logging, BadLevelNamesTheFieldAndTheChoices) {
  try {
    (void)parse_log_level("verbose");
    FAIL() << "expected ParameterError";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "log_level");
    const std::string what = e.what();
    EXPECT_NE(what.find("'verbose'"), std::string::npos) << what;
    EXPECT_NE(what.find("trace, debug, info, warn, error, critical, off"), std::string::npos) << what;
  }
  EXPECT_THROW(init_logging("x", "loud"), ParameterError);
}

TEST(Logging, WritesTheProcessNameLevelAndPidToTheFile) {
  const auto file = temp_path("a.log");
  auto logger = init_logging("bridge", "debug", file);
  EXPECT_EQ(spdlog::default_logger(), logger);
  spdlog::debug("armed at {} V", 12.5);
  spdlog::trace("not shown at debug");
  flush_logging();
  const std::string text = read_all(file);
  EXPECT_NE(text.find("bridge[" + std::to_string(::getpid()) + "] debug armed at 12.5 V"), std::string::npos) << text;
  EXPECT_EQ(text.find("not shown"), std::string::npos) << text;
  std::filesystem::remove(file);
}

TEST(Logging, SecondInitReplacesTheFirst) {
  const auto file = temp_path("b.log");
  (void)init_logging("compensator", "info");
  auto logger = init_logging("compensator", "warn", file);
  spdlog::info("dropped");
  spdlog::warn("kept");
  flush_logging();
  const std::string text = read_all(file);
  EXPECT_EQ(text.find("dropped"), std::string::npos) << text;
  EXPECT_NE(text.find("compensator["), std::string::npos) << text;
  EXPECT_NE(text.find("kept"), std::string::npos) << text;
  std::filesystem::remove(file);
}

TEST(Logging, UnwritableFileIsAParameterError) {
  try {
    (void)init_logging("x", "info", std::filesystem::path("/proc/hystloop/no/such/dir/x.log"));
    FAIL() << "expected ParameterError";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "log_file");
    EXPECT_NE(std::string(e.what()).find("/proc/hystloop/no/such/dir/x.log"), std::string::npos);
  }
}

TEST(Logging, AMissingFolderIsRefusedNotCreated) {
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "hystloop-no-such-folder-for-logs";
  std::filesystem::remove_all(folder);
  try {
    (void)init_logging("x", "info", folder / "x.log");
    FAIL() << "expected ParameterError";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "log_file");
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(folder));
}

}  // namespace
}  // namespace hystloop
