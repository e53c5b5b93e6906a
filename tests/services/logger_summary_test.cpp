// The logger's summary file: a summary that cannot be written leaves no stray
// temporary file, and the JSON reports the disk faults and the channels without a slot.
#include "logger/logger_summary.hpp"
#include "runtime/summary_file.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include <nlohmann/json.hpp>

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
  const std::string text = summary_json(s, channels);
  const auto json = nlohmann::json::parse(text);
  EXPECT_EQ(json["disk"]["ok"], false) << text;
  EXPECT_EQ(json["disk"]["errors"], 2);
  EXPECT_EQ(json["disk"]["last_error"], "disk full (write: No space left on device)");
  EXPECT_EQ(json["disk"]["events_lost"], 17);
  // 100 names offered; the table keeps kMaxChannels - kRigChannels of them, the rest are unknown.
  const std::size_t kept = ChannelTable::kMaxChannels - ChannelTable::kRigChannels;
  const auto& unknown = json["unknown_channels"];
  EXPECT_EQ(unknown["messages"], 100 - kept) << text;
  EXPECT_EQ(unknown["distinct"], 100 - kept);
  EXPECT_EQ(unknown["distinct_is_lower_bound"], false);
  ASSERT_FALSE(unknown["first"].empty());
  EXPECT_EQ(unknown["first"][0], "HX_J" + std::to_string(kept));
  const auto lines = summary_lines(s, channels);
  ASSERT_GE(lines.size(), 3u);
  EXPECT_EQ(lines[1].rfind("  DISK FAULT: 2 failed call(s), last disk full", 0), 0u) << lines[1];
}

// Forged but admissible ticks: two channels with more than 2^63 ticks missing each. Their total
// wrapped to a small number (2^64 - 2 with INT64_MIN/INT64_MAX ticks); it stops at UINT64_MAX.
// Text off the wire that is not UTF-8 (a channel name of raw bytes) is replaced, and the summary
// stays valid JSON instead of being lost.
TEST(LoggerSummary, ANameThatIsNotUtf8StillGivesValidJson) {
  ChannelTable channels(ChannelNames("HX_"));
  channels.find_or_add("HX_\xff\xfe");
  RecordingSummary s;
  s.recording = "run\x80";
  const std::string text = summary_json(s, channels);
  const auto json = nlohmann::json::parse(text);           // throws on invalid JSON or UTF-8
  EXPECT_EQ(json["recording"], "run\xef\xbf\xbd");         // U+FFFD
  for (const unsigned char c : text) EXPECT_LT(c, 0x80u);  // written as ASCII with \u escapes
}

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
  const std::string text = summary_json(RecordingSummary{}, channels);
  const auto json = nlohmann::json::parse(text);
  EXPECT_EQ(json["totals"]["missing"].get<std::uint64_t>(), kTop) << text.substr(0, 600);
  EXPECT_EQ(json["totals"]["skipped"], 0);
  EXPECT_EQ(json["totals"]["contract_violations"], 2);
  const auto& violations = json["channels"]["HX_SENSOR"]["sequence"]["contract_violations"];
  EXPECT_EQ(violations["negative_seq"], 1) << text;
  EXPECT_EQ(violations["seq_above_max"], 0);
  EXPECT_EQ(violations["tick_count"], 0);
  const auto lines = summary_lines(RecordingSummary{}, channels);
  ASSERT_GE(lines.size(), 2u);
  EXPECT_NE(lines[1].find("contract violations 1 (not checked for gaps: negative_seq 1 seq_above_max 0 tick_count 0)"),
            std::string::npos)
      << lines[1];
}

}  // namespace
}  // namespace hystloop
