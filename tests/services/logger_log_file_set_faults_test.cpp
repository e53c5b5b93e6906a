// LogFileSet on a failing disk (a full disk lost data silently). A LogFileIo that
// passes the calls to the real ones but has a byte budget (a disk that fills up), can stop
// writes short and fail fsync: every event must then be told written or lost, the files
// must end at an event boundary (lcm::LogFile reads each to its end), no empty file may be
// left, and writing must resume in a new file once there is space again.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <sys/stat.h>

#include <cerrno>
#include <filesystem>
#include <string>
#include <vector>

#include "logger/log_file_set.hpp"

namespace hystloop {
namespace {

namespace fs = std::filesystem;

class SmallDisk final : public LogFileIo {
 public:
  explicit SmallDisk(std::uint64_t free_bytes) : free_(free_bytes) {}
  std::uint64_t free_ = 0;
  bool short_without_error = false;  // a full disk answers 0 instead of ENOSPC
  int fsync_error = 0;
  int create_error = 0;
  std::uint64_t write_errors = 0;

  int create(const char* path) noexcept override {
    return create_error != 0 ? -create_error : posix_log_file_io().create(path);
  }
  ssize_t write(int fd, const void* data, std::size_t size) noexcept override {
    const std::size_t n = size < free_ ? size : static_cast<std::size_t>(free_);
    if (n == 0) {
      ++write_errors;
      return short_without_error ? 0 : -ENOSPC;
    }
    const ssize_t rc = posix_log_file_io().write(fd, data, n);
    if (rc > 0) free_ -= static_cast<std::uint64_t>(rc);
    return rc;
  }
  int truncate(int fd, std::uint64_t size) noexcept override {
    struct stat st {};
    ::fstat(fd, &st);
    const int rc = posix_log_file_io().truncate(fd, size);
    if (rc == 0 && static_cast<std::uint64_t>(st.st_size) > size)
      free_ += static_cast<std::uint64_t>(st.st_size) - size;
    return rc;
  }
  int fsync(int fd) noexcept override { return fsync_error != 0 ? -fsync_error : posix_log_file_io().fsync(fd); }
  int close(int fd) noexcept override { return posix_log_file_io().close(fd); }
  int remove(const char* path) noexcept override {
    struct stat st {};
    const bool known = ::stat(path, &st) == 0;
    const int rc = posix_log_file_io().remove(path);
    if (rc == 0 && known) free_ += static_cast<std::uint64_t>(st.st_size);
    return rc;
  }
};

struct Fates final : LogFileSet::Listener {
  std::uint64_t n_written = 0, n_lost = 0, bytes = 0;
  void written(std::uint32_t, std::size_t payload) noexcept override {
    ++n_written;
    bytes += payload;
  }
  void lost(std::uint32_t) noexcept override { ++n_lost; }
};

class LogFileSetFaultTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("logger_faults_test_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Every file in the directory, read to its end: events read; each file must be non-empty,
  // hold exactly the events the set says, and end where its last event ends.
  std::uint64_t read_directory(const std::vector<LogFileInfo>& files) {
    std::uint64_t total = 0;
    std::size_t on_disk = 0;
    for (const auto& entry : fs::directory_iterator(dir_)) {
      ++on_disk;
      EXPECT_GT(fs::file_size(entry.path()), 0u) << entry.path() << " left empty";
    }
    EXPECT_EQ(on_disk, files.size());
    for (const LogFileInfo& f : files) {
      lcm::LogFile log(f.path.string(), "r");
      EXPECT_TRUE(log.good()) << f.path;
      std::uint64_t n = 0, bytes = 0;
      while (const lcm::LogEvent* ev = log.readNextEvent()) {
        EXPECT_EQ(ev->eventnum, static_cast<std::int64_t>(n)) << f.path;
        bytes += LogFileSet::event_bytes(ev->channel.size(), static_cast<std::size_t>(ev->datalen));
        ++n;
      }
      EXPECT_EQ(n, f.events) << f.path;
      EXPECT_EQ(bytes, fs::file_size(f.path)) << f.path << ": does not end at an event boundary";
      EXPECT_EQ(fs::file_size(f.path), f.bytes) << f.path;
      total += n;
    }
    return total;
  }

  fs::path dir_;
};

constexpr std::time_t kStart = 1700000000;
const std::string kPayload(300, 'p');

bool write_one(LogFileSet& set, int i, double now_s) {
  return set.write("HX_SENSOR", 9, kPayload.data(), kPayload.size(), 1000 + i, now_s, 0);
}

TEST_F(LogFileSetFaultTest, AFullDiskIsSeenCountedCutBackAndWritingResumesInANewFile) {
  SmallDisk disk(10'000 + 123);  // ~29 events of 337 bytes, then a cut in the middle of one
  Fates fates;
  LogFileSet set(dir_, "", RotationPolicy{4000, 0.0}, kStart, 0.0, &fates, disk);
  int offered = 0;
  for (int i = 0; i < 100; ++i, ++offered) {
    write_one(set, i, 0.01 * i);
    if (i % 5 == 4) set.flush();
  }
  DiskFaults f = set.faults();
  EXPECT_GE(f.errors, 1u);
  EXPECT_FALSE(f.writing);
  EXPECT_EQ(f.last_op, DiskOp::kWrite);
  EXPECT_EQ(f.reason(), "disk full (write: No space left on device)");
  EXPECT_GT(f.events_lost, 0u);
  EXPECT_GE(f.files_truncated, 1u);
  EXPECT_EQ(fates.n_written + fates.n_lost, static_cast<std::uint64_t>(offered));
  EXPECT_EQ(fates.n_lost, f.events_lost);
  EXPECT_EQ(read_directory(set.files()), fates.n_written);  // no event reported written that is not on disk

  // Still full one second later: the retry file gets nothing and is removed again.
  for (int i = 0; i < 5; ++i, ++offered) write_one(set, i, 1.5);
  set.flush();
  EXPECT_FALSE(set.faults().writing);
  EXPECT_GE(set.faults().files_removed, 1u);
  EXPECT_EQ(read_directory(set.files()), fates.n_written);

  // Space again: after the retry interval a new file takes the events.
  disk.free_ = 1'000'000;
  const std::size_t files_before = set.files().size();
  for (int i = 0; i < 20; ++i, ++offered) write_one(set, i, 3.0 + 0.001 * i);
  set.close();
  f = set.faults();
  EXPECT_TRUE(f.writing);
  EXPECT_EQ(f.recoveries, 1u);
  EXPECT_GT(set.files().size(), files_before);
  EXPECT_EQ(fates.n_written + fates.n_lost, static_cast<std::uint64_t>(offered));
  EXPECT_EQ(read_directory(set.files()), fates.n_written);
  EXPECT_EQ(fates.bytes, fates.n_written * kPayload.size());
}

TEST_F(LogFileSetFaultTest, AShortWriteWithoutAnErrorIsAFaultToo) {
  SmallDisk disk(5'000);
  disk.short_without_error = true;
  Fates fates;
  LogFileSet set(dir_, "", RotationPolicy{}, kStart, 0.0, &fates, disk);
  for (int i = 0; i < 30; ++i) write_one(set, i, 0.0);
  set.close();
  EXPECT_EQ(set.faults().reason(), "short write (write: the kernel took fewer bytes than given)");
  EXPECT_EQ(fates.n_written, 5000u / 337u);
  EXPECT_EQ(fates.n_lost, 30u - 5000u / 337u);
  EXPECT_EQ(read_directory(set.files()), fates.n_written);
}

TEST_F(LogFileSetFaultTest, AFileThatGetsNoCompleteEventIsRemoved) {
  SmallDisk disk(100);  // not even one event
  Fates fates;
  LogFileSet set(dir_, "", RotationPolicy{}, kStart, 0.0, &fates, disk);
  for (int i = 0; i < 10; ++i) write_one(set, i, 0.0);
  set.close();
  EXPECT_EQ(fates.n_written, 0u);
  EXPECT_EQ(fates.n_lost, 10u);
  EXPECT_TRUE(set.files().empty());
  EXPECT_EQ(set.faults().files_removed, 1u);
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(LogFileSetFaultTest, AnEventLargerThanTheBufferCutMidwayIsCutBack) {
  SmallDisk disk(1000 + LogFileSet::kBufferBytes / 2);
  Fates fates;
  LogFileSet set(dir_, "", RotationPolicy{}, kStart, 0.0, &fates, disk);
  ASSERT_TRUE(write_one(set, 0, 0.0));
  const std::string big(LogFileSet::kBufferBytes + 10, 'b');
  EXPECT_FALSE(set.write("HX_BIG", 6, big.data(), big.size(), 2, 0.0, 1));
  set.close();
  EXPECT_EQ(fates.n_written, 1u);
  EXPECT_EQ(fates.n_lost, 1u);
  EXPECT_EQ(set.faults().files_truncated, 1u);
  EXPECT_EQ(read_directory(set.files()), 1u);
}

TEST_F(LogFileSetFaultTest, FsyncFailingAtRotationIsAFaultWithUnconfirmedEvents) {
  SmallDisk disk(1'000'000);
  disk.fsync_error = EIO;
  Fates fates;
  LogFileSet set(dir_, "", RotationPolicy{1000, 0.0}, kStart, 0.0, &fates, disk);
  for (int i = 0; i < 4; ++i) write_one(set, i, 0.0);  // 2 fit in a file: the third rotates
  const DiskFaults f = set.faults();
  EXPECT_EQ(f.last_op, DiskOp::kFsync);
  EXPECT_EQ(f.reason(), "I/O error (fsync: Input/output error)");
  EXPECT_EQ(f.unconfirmed_events, 2u);
  EXPECT_EQ(fates.n_written, 2u);  // the kernel took them: written, but unconfirmed
  EXPECT_EQ(fates.n_lost, 2u);     // refused until the retry
}

TEST_F(LogFileSetFaultTest, ARotationThatCannotCreateTheNextFileRefusesUntilTheRetry) {
  SmallDisk disk(1'000'000);
  Fates fates;
  LogFileSet set(dir_, "", RotationPolicy{1000, 0.0}, kStart, 0.0, &fates, disk);
  write_one(set, 0, 0.0);
  write_one(set, 1, 0.0);
  disk.create_error = ENOSPC;
  EXPECT_FALSE(write_one(set, 2, 0.5));  // rotation: the next file cannot be created
  EXPECT_EQ(set.faults().last_op, DiskOp::kCreate);
  EXPECT_FALSE(write_one(set, 3, 1.0));  // waiting for the retry
  disk.create_error = 0;
  EXPECT_TRUE(write_one(set, 4, 1.6));
  set.close();
  EXPECT_EQ(fates.n_written, 3u);
  EXPECT_EQ(fates.n_lost, 2u);
  EXPECT_EQ(set.files().size(), 2u);
  EXPECT_EQ(read_directory(set.files()), 3u);
}

}  // namespace
}  // namespace hystloop
