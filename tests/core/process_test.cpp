#include "core/process.hpp"

#include <gtest/gtest.h>
#include <poll.h>
#include <sys/mman.h>
#include <sched.h>

#include <csignal>
#include <cstring>
#include <vector>

#include "core/errors.hpp"

namespace hystloop {
namespace {

bool fd_readable(int fd, int timeout_ms) {
  pollfd p{fd, POLLIN, 0};
  return ::poll(&p, 1, timeout_ms) == 1 && (p.revents & POLLIN);
}

class StopHandling : public ::testing::Test {
 protected:
  void SetUp() override {
    install_stop_handlers();
    clear_stop_request();
  }
  void TearDown() override { clear_stop_request(); }
};

TEST_F(StopHandling, SigtermSetsTheFlagAndWakesThePollLoop) {
  ASSERT_GE(stop_fd(), 0);
  EXPECT_FALSE(stop_requested());
  EXPECT_FALSE(fd_readable(stop_fd(), 0));
  ASSERT_EQ(std::raise(SIGTERM), 0);
  EXPECT_TRUE(stop_requested());
  EXPECT_EQ(stop_signal(), SIGTERM);
  EXPECT_TRUE(fd_readable(stop_fd(), 100));
}

TEST_F(StopHandling, SigintToo) {
  ASSERT_EQ(std::raise(SIGINT), 0);
  EXPECT_TRUE(stop_requested());
  EXPECT_EQ(stop_signal(), SIGINT);
}

TEST_F(StopHandling, RequestStopAndClear) {
  install_stop_handlers();  // idempotent
  request_stop();
  EXPECT_TRUE(stop_requested());
  EXPECT_EQ(stop_signal(), 0);
  EXPECT_TRUE(fd_readable(stop_fd(), 100));
  clear_stop_request();
  EXPECT_FALSE(stop_requested());
  EXPECT_FALSE(fd_readable(stop_fd(), 0));
}

TEST_F(StopHandling, SecondSignalKillsTheProcess) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        std::raise(SIGTERM);  // first: a stop request
        std::raise(SIGTERM);  // second: the default action
        std::_Exit(0);
      },
      ::testing::KilledBySignal(SIGTERM), "");
}

TEST(Process, LockMemoryReportsEitherWay) {
  const SetupStatus s = lock_memory();
  EXPECT_FALSE(s.detail.empty());
  if (s.ok) {
    ::munlockall();
  } else {
    EXPECT_NE(s.detail.find("mlockall refused"), std::string::npos) << s.detail;
  }
}

TEST(Process, RealtimePriorityIsNonFatalAndReversible) {
  EXPECT_THROW(set_realtime_priority(0), ParameterError);
  EXPECT_THROW(set_realtime_priority(100), ParameterError);
  const SetupStatus s = set_realtime_priority(1);
  EXPECT_FALSE(s.detail.empty());
  if (s.ok) {
    EXPECT_EQ(sched_getscheduler(0), SCHED_FIFO);
  }
  EXPECT_TRUE(set_normal_priority().ok);
  EXPECT_EQ(sched_getscheduler(0), SCHED_OTHER);
}

TEST(Process, CpuAffinityRoundTrips) {
  const std::vector<int> before = current_cpu_affinity();
  ASSERT_FALSE(before.empty());
  const SetupStatus one = set_cpu_affinity({before.front()});
  EXPECT_TRUE(one.ok) << one.detail;
  EXPECT_EQ(current_cpu_affinity(), std::vector<int>{before.front()});
  EXPECT_TRUE(set_cpu_affinity(before).ok);
  EXPECT_EQ(current_cpu_affinity(), before);
  EXPECT_THROW(set_cpu_affinity({}), ParameterError);
  EXPECT_THROW(set_cpu_affinity({-1}), ParameterError);
  EXPECT_THROW(set_cpu_affinity({CPU_SETSIZE}), ParameterError);
}

TEST(Process, ResourceUsageSeesCpuTimeAndMemory) {
  const ResourceUsage before = read_resource_usage();
  EXPECT_GT(before.peak_rss_bytes, 0);
  // Touch 64 MiB and burn a little CPU: peak RSS and CPU time must not go down,
  // and peak RSS must rise by most of what was touched.
  std::vector<char> block(64u << 20);
  std::memset(block.data(), 1, block.size());
  volatile double sink = 0;
  for (int i = 0; i < 5'000'000; ++i) sink = sink + 1e-9 * i;
  const ResourceUsage after = read_resource_usage();
  EXPECT_GE(after.peak_rss_bytes, before.peak_rss_bytes + (48 << 20));
  EXPECT_GE(after.user_cpu_s + after.system_cpu_s, before.user_cpu_s + before.system_cpu_s);
  EXPECT_GT(after.user_cpu_s + after.system_cpu_s, 0.0);
  EXPECT_GE(after.minor_faults, before.minor_faults);
  EXPECT_EQ(block[block.size() / 2], 1);
}

TEST(Process, HostName) { EXPECT_FALSE(host_name().empty()); }

}  // namespace
}  // namespace hystloop
