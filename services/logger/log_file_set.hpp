#pragma once
// The log files of one recording: LCM event logs (lcm_eventlog_t, the format lcm-logger
// writes and lcm-logplayer / lcm-spy read), rotated by size and age. Names:
//
//   <dir>/<file_prefix>hystloop-YYYYmmdd-HHMMSS.NNN.lcmlog
//
// with the local start time of the recording and NNN the file's number in it (000, 001,
// ...; more digits past 999), so a directory listing sorts in recording order. The base
// name gets "-1", "-2", ... appended if that recording name is taken. A file is rotated
// *before* an event that would take it past `max_file_bytes`, or once it is older than
// `max_file_s`; an event is never split, and a file never left empty by rotation.
//
// Used by the disk thread only, except current_file()/file_count() (any thread).

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

struct _lcm_eventlog_t;

namespace hystloop {

struct RotationPolicy {
  std::uint64_t max_file_bytes = 0;  // 0 = no size limit
  double max_file_s = 0.0;           // 0 = no age limit [s]
};

struct LogFileInfo {
  std::filesystem::path path;
  std::uint64_t events = 0;
  std::uint64_t bytes = 0;  // on disk, LCM's per-event framing included
};

class LogFileSet {
 public:
  // Creates `dir` if needed, picks the recording's base name from `start_time` and opens
  // the first file. Throws std::runtime_error naming the path if it cannot.
  LogFileSet(std::filesystem::path dir, std::string file_prefix, RotationPolicy policy,
             std::time_t start_time, double now_s);
  ~LogFileSet();
  LogFileSet(const LogFileSet&) = delete;
  LogFileSet& operator=(const LogFileSet&) = delete;

  // Writes one event, rotating first if a limit says so. `now_s` is a monotonic time [s].
  // False if the event could not be written (the caller counts it); after a failed
  // open, a new file is tried at most once a second.
  bool write(const char* channel, std::size_t channel_length, const void* data, std::size_t size,
             std::int64_t utime, double now_s) noexcept;

  // Pushes buffered events to the kernel (a crash then loses at most one flush interval).
  void flush() noexcept;
  // Flushes, fsyncs and closes the current file; write() afterwards opens no new one.
  void close() noexcept;

  // "<dir>/<file_prefix>hystloop-YYYYmmdd-HHMMSS" (the summary goes to base + ".summary.json").
  const std::filesystem::path& base_path() const noexcept { return base_; }
  // Files so far; the disk thread appends, so call after close() or from the disk thread.
  const std::vector<LogFileInfo>& files() const noexcept { return files_; }
  // Any thread.
  std::filesystem::path current_file() const;
  std::size_t file_count() const;
  std::uint64_t open_failures() const noexcept { return open_failures_; }

  // The bytes an event occupies in the file (LCM's framing: magic, number, time, lengths).
  static std::uint64_t event_bytes(std::size_t channel_length, std::size_t size) noexcept {
    return 28u + channel_length + size;
  }

 private:
  bool open_next(double now_s) noexcept;
  void close_current() noexcept;

  std::filesystem::path base_;
  RotationPolicy policy_;
  _lcm_eventlog_t* log_ = nullptr;
  std::unique_ptr<char[]> stdio_buffer_;
  std::vector<LogFileInfo> files_;
  double opened_s_ = 0.0;
  double last_open_attempt_s_ = -1e300;
  std::uint64_t open_failures_ = 0;
  bool closed_ = false;
  mutable std::mutex names_mutex_;  // guards files_' growth against current_file()
};

}  // namespace hystloop
