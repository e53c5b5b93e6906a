#include "logger/log_file_io.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>

namespace hystloop {

namespace {
int result(long rc) noexcept { return rc < 0 ? -errno : static_cast<int>(rc); }

class PosixLogFileIo final : public LogFileIo {
 public:
  int create(const char* path) noexcept override {
    return result(::open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644));
  }
  ssize_t write(int fd, const void* data, std::size_t size) noexcept override {
    ssize_t rc = 0;
    do {
      rc = ::write(fd, data, size);
    } while (rc < 0 && errno == EINTR);
    return rc < 0 ? -errno : rc;
  }
  int truncate(int fd, std::uint64_t size) noexcept override {
    return result(::ftruncate(fd, static_cast<off_t>(size)));
  }
  int fsync(int fd) noexcept override { return result(::fsync(fd)); }
  int close(int fd) noexcept override { return result(::close(fd)); }
  int remove(const char* path) noexcept override { return result(::unlink(path)); }
};
}  // namespace

LogFileIo& posix_log_file_io() noexcept {
  static PosixLogFileIo io;
  return io;
}

}  // namespace hystloop
