#pragma once
// The system calls LogFileSet makes on its files, behind an interface so that a test can
// make any of them fail (ENOSPC after N bytes, EIO on fsync, a short write...). Every call
// returns what the system call does, with the error as a negative errno instead of -1.

#include <cstddef>
#include <cstdint>
#include <sys/types.h>

namespace hystloop {

class LogFileIo {
 public:
  virtual ~LogFileIo() = default;
  // Creates `path` for writing; fails if it exists. A file descriptor, or -errno.
  virtual int create(const char* path) noexcept = 0;
  // Bytes written (possibly fewer than `size`), or -errno.
  virtual ssize_t write(int fd, const void* data, std::size_t size) noexcept = 0;
  virtual int truncate(int fd, std::uint64_t size) noexcept = 0;  // 0 or -errno
  virtual int fsync(int fd) noexcept = 0;                         // 0 or -errno
  virtual int close(int fd) noexcept = 0;                         // 0 or -errno; fd released either way
  virtual int remove(const char* path) noexcept = 0;              // 0 or -errno
};

// The real calls (open(O_CREAT|O_EXCL), write, ftruncate, fsync, close, unlink).
LogFileIo& posix_log_file_io() noexcept;

}  // namespace hystloop
