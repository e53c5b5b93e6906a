// The logger's summary file: a summary that cannot be written leaves no stray
// temporary file, and the JSON reports the disk faults and the channels without a slot.
#include "logger/logger_summary.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "lcm/message_checks.hpp"

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

// Forged but admissible ticks: two channels with more than 2^63 ticks missing each. Their total
// wrapped to a small number (2^64 - 2 with INT64_MIN/INT64_MAX ticks); it stops at UINT64_MAX.
TEST(LoggerSummary, TheTotalOfMissingTicksSaturatesInsteadOfWrapping) {
  ChannelTable channels(ChannelNames("HX_"));
  constexpr std::uint64_t kTop = std::numeric_limits<std::uint64_t>::max();
  for (std::size_t i : {std::size_t{0}, std::size_t{1}}) {  // HX_SENSOR, HX_COMMAND
    SequenceGapDetector& q = channels[i].sequence;
    // 1100 gaps of 2^53 - 1 ticks: above 2^63, below 2^64 (the channel's own count is exact).
    for (int k = 0; k < 1100; ++k) {
      q.observe(0, 1);
      q.observe(kMaxTick, 1);
    }
    ASSERT_GT(q.missing(), kTop / 2);
    ASSERT_LT(q.missing(), kTop);
    q.observe(-1, 1);  // forbidden by the contract: counted, not summed
  }
  const std::string json = summary_json(RecordingSummary{}, channels);
  EXPECT_NE(json.find("\"missing\": " + std::to_string(kTop) + ", \"skipped\": 0, \"contract_violations\": 2}"),
            std::string::npos)
      << json.substr(0, 600);
  EXPECT_NE(json.find("\"contract_violations\": {\"negative_seq\": 1, \"seq_above_max\": 0, \"tick_count\": 0}"),
            std::string::npos)
      << json;
  const auto lines = summary_lines(RecordingSummary{}, channels);
  ASSERT_GE(lines.size(), 2u);
  EXPECT_NE(lines[1].find("contract violations 1 (not checked for gaps: negative_seq 1 seq_above_max 0 tick_count 0)"),
            std::string::npos)
      << lines[1];
}

}  // namespace
}  // namespace hystloop
