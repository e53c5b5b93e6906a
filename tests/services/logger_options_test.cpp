#include "logger/logger_options.hpp"

#include <gtest/gtest.h>

#include <string>

#include "core/config.hpp"

namespace hystloop {
namespace {

std::string error_of(const Config& config) {
  try {
    read_logger_options(config);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(LoggerOptions, DefaultsWithAnEmptyConfiguration) {
  const LoggerOptions o = read_logger_options(Config());
  EXPECT_EQ(o.out_dir, "logs");
  EXPECT_EQ(o.max_file_mb, 1024.0);
  EXPECT_EQ(o.max_file_s, 0.0);
  EXPECT_TRUE(o.summary_file.empty());
  EXPECT_TRUE(o.channels.empty());
  EXPECT_EQ(o.lcm_queue, 20000);
  EXPECT_EQ(o.restart_threshold, 10000);
  EXPECT_EQ(o.command_resume_s, 0.1);
}

TEST(LoggerOptions, ReadsTheFileAndIgnoresOtherSections) {
  const Config c = Config::from_string(
      "logger:\n  out_dir: /data/rig1\n  max_file_mb: 0.5\n  max_file_s: 60\n  channels: 'HX_S.*'\n"
      "bridge:\n  u_max_V: 120\n",
      "rig.yaml");
  const LoggerOptions o = read_logger_options(c);
  EXPECT_EQ(o.out_dir, "/data/rig1");
  EXPECT_EQ(o.max_file_mb, 0.5);
  EXPECT_EQ(o.max_file_s, 60.0);
  EXPECT_EQ(o.channels, "HX_S.*");
}

TEST(LoggerOptions, BadValuesNameTheField) {
  EXPECT_EQ(error_of(Config::from_string("logger:\n  max_file_mb: -1\n", "rig.yaml")),
            "rig.yaml: logger.max_file_mb: must be in [0, 1e+09] (got -1)");
  EXPECT_NE(error_of(Config::from_string("logger:\n  queue_mb: 0\n", "rig.yaml")).find("logger.queue_mb"),
            std::string::npos);
  EXPECT_NE(error_of(Config::from_string("logger:\n  lcm_queue: 0\n", "rig.yaml")).find("logger.lcm_queue"),
            std::string::npos);
  EXPECT_NE(error_of(Config::from_string("logger:\n  file_prefix: a/b\n", "rig.yaml")).find("logger.file_prefix"),
            std::string::npos);
  EXPECT_NE(error_of(Config::from_string("logger:\n  flush_interval_s: 0\n")).find("logger.flush_interval_s"),
            std::string::npos);
  EXPECT_NE(error_of(Config::from_string("logger:\n  command_resume_s: -0.5\n")).find("logger.command_resume_s"),
            std::string::npos);
}

// --summary DIR failed only at shutdown, after the whole recording.
TEST(LoggerOptions, ASummaryPathThatIsADirectoryIsRefusedAtOnce) {
  EXPECT_NE(error_of(Config::from_string("logger:\n  summary: /tmp\n")).find("logger.summary: '/tmp' is a directory"),
            std::string::npos);
  EXPECT_NE(error_of(Config::from_string("logger:\n  summary: /nonexistent/dir/\n")).find("logger.summary"),
            std::string::npos);
  EXPECT_EQ(error_of(Config::from_string("logger:\n  summary: /nonexistent/dir/run.json\n")), "");
}

// a bad --channels regex was found only when LCM refused it (exit 1, not 2).
TEST(LoggerOptions, AChannelRegexLcmCannotCompileIsRefused) {
  EXPECT_NE(error_of(Config::from_string("logger:\n  channels: 'HX_(['\n"))
                .find("logger.channels: not a regular expression LCM accepts"),
            std::string::npos);
  EXPECT_EQ(error_of(Config::from_string("logger:\n  channels: 'HX_(SENSOR|COMMAND)|OTHER_.*'\n")), "");
}

TEST(LoggerOptions, UnknownLoggerKeyGetsASuggestion) {
  const std::string e = error_of(Config::from_string("logger:\n  max_file_sec: 5\n", "rig.yaml"));
  EXPECT_NE(e.find("logger.max_file_sec"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'logger.max_file_s'"), std::string::npos) << e;
}

TEST(LoggerOptions, FlagsOverrideTheFileAndKeepTextAsText) {
  Config c = Config::from_string("logger:\n  max_file_mb: 5\n  channels: 'HX_.*'\n");
  LoggerFlags flags;
  flags.values["max_file_mb"] = "7.5";
  flags.values["channels"] = "[A-Z]+_SENSOR";  // YAML would read this as a list unless quoted
  flags.values["file_prefix"] = "it's_";
  apply_logger_flags(flags, c);
  const LoggerOptions o = read_logger_options(c);
  EXPECT_EQ(o.max_file_mb, 7.5);
  EXPECT_EQ(o.channels, "[A-Z]+_SENSOR");
  EXPECT_EQ(o.file_prefix, "it's_");
}

TEST(LoggerOptions, CommandLineFlagsParse) {
  CLI::App app;
  LoggerFlags flags;
  add_logger_options(app, flags);
  const char* argv[] = {"hystloop-logger", "--out-dir", "/tmp/x", "--max-file-s", "30", "--command-resume-s", "0"};
  app.parse(7, const_cast<char**>(argv));
  Config c;
  apply_logger_flags(flags, c);
  const LoggerOptions o = read_logger_options(c);
  EXPECT_EQ(o.out_dir, "/tmp/x");
  EXPECT_EQ(o.max_file_s, 30.0);
  EXPECT_EQ(o.command_resume_s, 0.0);  // every command jump a gap
}

}  // namespace
}  // namespace hystloop
