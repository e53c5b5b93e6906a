#include "logger/log_file_set.hpp"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace hystloop {
namespace {

namespace fs = std::filesystem;

class LogFileSetTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("logger_file_set_test_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Reads every event of `files` in order: channel + payload.
  static std::vector<std::pair<std::string, std::string>> read_all(const std::vector<LogFileInfo>& files) {
    std::vector<std::pair<std::string, std::string>> events;
    for (const LogFileInfo& f : files) {
      lcm::LogFile log(f.path.string(), "r");
      EXPECT_TRUE(log.good()) << f.path;
      std::uint64_t n = 0;
      while (const lcm::LogEvent* ev = log.readNextEvent()) {
        events.emplace_back(ev->channel, std::string(static_cast<const char*>(ev->data), ev->datalen));
        ++n;
      }
      EXPECT_EQ(n, f.events) << f.path;
      EXPECT_EQ(fs::file_size(f.path), f.bytes) << f.path;
    }
    return events;
  }

  fs::path dir_;
};

constexpr std::time_t kStart = 1700000000;  // a fixed start time: names are predictable

TEST_F(LogFileSetTest, RotatesBySizeWithoutSplittingOrLosingEvents) {
  LogFileSet set(dir_, "pre_", RotationPolicy{2000, 0.0}, kStart, 0.0);
  std::mt19937_64 rng(3);
  std::vector<std::pair<std::string, std::string>> written;
  for (int i = 0; i < 300; ++i) {
    const std::string channel = (i % 2) ? "HX_SENSOR" : "HX_COMMAND";
    std::string data(static_cast<std::size_t>(rng() % 120), '\0');
    for (char& c : data) c = static_cast<char>(rng());
    ASSERT_TRUE(set.write(channel.c_str(), channel.size(), data.data(), data.size(), 1000 + i, 0.0));
    written.emplace_back(channel, data);
  }
  set.close();
  ASSERT_GT(set.files().size(), 5u);
  for (std::size_t i = 0; i < set.files().size(); ++i) {
    const LogFileInfo& f = set.files()[i];
    EXPECT_LE(f.bytes, 2000u);
    EXPECT_GT(f.events, 0u);
    char expected_name[64];
    std::snprintf(expected_name, sizeof expected_name, ".%03zu.lcmlog", i);
    EXPECT_NE(f.path.filename().string().find(expected_name), std::string::npos) << f.path;
    EXPECT_EQ(f.path.filename().string().rfind("pre_hystloop-20", 0), 0u) << f.path;
  }
  EXPECT_EQ(read_all(set.files()), written);
}

TEST_F(LogFileSetTest, RotatesByAgeOnTheTimeItIsGiven) {
  LogFileSet set(dir_, "", RotationPolicy{0, 1.0}, kStart, 100.0);
  const char data[4] = {1, 2, 3, 4};
  // Time is an argument: 10 events 0.25 s apart -> a new file every 4 events.
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(set.write("HX_X", 4, data, sizeof data, i, 100.0 + 0.25 * i));
  set.close();
  ASSERT_EQ(set.files().size(), 3u);
  EXPECT_EQ(set.files()[0].events, 4u);
  EXPECT_EQ(set.files()[1].events, 4u);
  EXPECT_EQ(set.files()[2].events, 2u);
}

TEST_F(LogFileSetTest, AnEventLargerThanTheLimitGetsAFileOfItsOwn) {
  LogFileSet set(dir_, "", RotationPolicy{100, 0.0}, kStart, 0.0);
  const std::string big(500, 'x');
  ASSERT_TRUE(set.write("HX_A", 4, "ab", 2, 1, 0.0));
  ASSERT_TRUE(set.write("HX_A", 4, big.data(), big.size(), 2, 0.0));
  ASSERT_TRUE(set.write("HX_A", 4, "cd", 2, 3, 0.0));
  set.close();
  ASSERT_EQ(set.files().size(), 3u);
  EXPECT_EQ(set.files()[1].events, 1u);
}

TEST_F(LogFileSetTest, ASecondRecordingWithTheSameStartGetsItsOwnName) {
  fs::path first;
  {
    LogFileSet a(dir_, "", RotationPolicy{}, kStart, 0.0);
    first = a.base_path();
    ASSERT_TRUE(a.write("HX_A", 4, "ab", 2, 1, 0.0));
  }
  LogFileSet b(dir_, "", RotationPolicy{}, kStart, 0.0);
  EXPECT_EQ(b.base_path().string(), first.string() + "-1");
  EXPECT_EQ(b.current_file().string(), first.string() + "-1.000.lcmlog");
  b.close();
  EXPECT_FALSE(b.write("HX_A", 4, "ab", 2, 1, 0.0));  // closed: nothing reopens
  EXPECT_EQ(b.file_count(), 0u);                      // it never held an event: removed at close, no empty file left
  EXPECT_FALSE(fs::exists(first.string() + "-1.000.lcmlog"));
}

TEST_F(LogFileSetTest, UnwritableDirectoryIsRefusedAtStart) {
  fs::create_directories(dir_);
  const fs::path file = dir_ / "plain_file";
  std::FILE* f = std::fopen(file.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fclose(f);
  EXPECT_THROW(LogFileSet(file / "sub", "", RotationPolicy{}, kStart, 0.0), std::runtime_error);
}

}  // namespace
}  // namespace hystloop
