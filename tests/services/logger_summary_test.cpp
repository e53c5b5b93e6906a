// The logger's summary file: a summary that cannot be written leaves no stray
// temporary file, and the JSON reports the disk faults and the channels without a slot.
#include "logger/logger_summary.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <string>

namespace hystloop {
namespace {

namespace fs = std::filesystem;

TEST(LoggerSummary, AFailedWriteLeavesNoTemporaryFile) {
  const fs::path dir = fs::temp_directory_path() / ("logger_summary_test_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "taken");
  std::ofstream(dir / "taken" / "x") << "x";  // a non-empty directory where the summary should go
  EXPECT_THROW(write_file_atomically(dir / "taken", "{}\n"), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir / "taken.tmp"));
  write_file_atomically(dir / "ok.json", "{}\n");
  EXPECT_TRUE(fs::exists(dir / "ok.json"));
  EXPECT_FALSE(fs::exists(dir / "ok.json.tmp"));
  fs::remove_all(dir);
}

TEST(LoggerSummary, TheJsonSaysTheDiskFaultAndTheUnknownChannels) {
  ChannelTable channels(ChannelNames("HX_"));
  for (int i = 0; i < 100; ++i) {
    std::string name = "HX_J";
    name += std::to_string(i);
    channels.find_or_add(name.c_str());
  }
  RecordingSummary s;
  s.disk.errors = 2;
  s.disk.events_lost = 17;
  s.disk.last_errno = ENOSPC;
  s.disk.last_op = DiskOp::kWrite;
  const std::string json = summary_json(s, channels);
  EXPECT_NE(json.find("\"disk\": {\"ok\": false, \"errors\": 2, \"last_error\": \"disk full (write: No space left on "
                      "device)\", \"events_lost\": 17"),
            std::string::npos)
      << json;
  // 100 names offered; the table keeps kMaxChannels - kRigChannels of them, the rest are unknown.
  const std::size_t kept = ChannelTable::kMaxChannels - ChannelTable::kRigChannels;
  const std::string unknown = std::to_string(100 - kept);
  EXPECT_NE(json.find("\"unknown_channels\": {\"messages\": " + unknown + ", \"distinct\": " + unknown +
                      ", \"distinct_is_lower_bound\": false, \"first\": [\"HX_J" + std::to_string(kept) + "\""),
            std::string::npos)
      << json;
  const auto lines = summary_lines(s, channels);
  ASSERT_GE(lines.size(), 3u);
  EXPECT_EQ(lines[1].rfind("  DISK FAULT: 2 failed call(s), last disk full", 0), 0u) << lines[1];
}

}  // namespace
}  // namespace hystloop
