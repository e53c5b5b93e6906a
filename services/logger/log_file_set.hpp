#pragma once
// The log files of one recording: LCM event logs (the format lcm-logger writes and
// lcm-logplayer / lcm::LogFile read), rotated by size and age. Names:
//
//   <dir>/<file_prefix>hystloop-YYYYmmdd-HHMMSS.NNN.lcmlog
//
// with the local start time of the recording and NNN the file's number in it (000, 001,
// ...; more digits past 999), so a directory listing sorts in recording order. The base
// name gets "-1", "-2", ... appended if that recording name is taken. A file is rotated
// *before* an event that would take it past `max_file_bytes`, or once it is older than
// `max_file_s`; an event is never split, and a file never left empty by rotation.
//
// Events are framed here and gathered in a buffer that goes to the kernel in one write()
// when it is full or at flush(). An event counts as written only once the kernel has taken
// all of its bytes: the Listener hears written() then, or lost() if it could not be written.
// Any failed call (create, write or a short write, ftruncate, fsync, close) is a disk fault:
// counted (faults()), the file is cut back to its last complete event (so every reader reads
// it to its end), closed, and removed if it holds none; the events not written are lost.
// Nothing is written for kRetryInterval_s (events are refused and lost), then a new file is
// tried -- writing resumes by itself once there is space again. fsync/close failing after
// the kernel took a file's events leaves them counted as written but "unconfirmed".
//
// Used by the disk thread only, except current_file(), file_count() and faults() (any thread).

#include <atomic>
#include <cstdint>
#include <ctime>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "logger/log_file_io.hpp"

namespace hystloop {

struct RotationPolicy {
  std::uint64_t max_file_bytes = 0;  // 0 = no size limit
  double max_file_s = 0.0;           // 0 = no age limit [s]
};

struct LogFileInfo {
  std::filesystem::path path;
  std::uint64_t events = 0;  // complete events the kernel took
  std::uint64_t bytes = 0;   // their bytes, LCM's per-event framing included: the file's size
};

// The call that failed last.
enum class DiskOp : std::uint8_t { kNone, kCreate, kWrite, kTruncate, kFsync, kClose };

// A snapshot of the disk faults of a recording.
struct DiskFaults {
  std::uint64_t errors = 0;           // failed calls (a short write counts as a failed write)
  std::uint64_t events_lost = 0;      // events not written because of them (also those refused while waiting to retry)
  std::uint64_t files_truncated = 0;  // files cut back to their last complete event
  std::uint64_t files_removed = 0;    // files left without any complete event, removed
  std::uint64_t unconfirmed_events = 0;  // in files whose fsync or close failed
  std::uint64_t recoveries = 0;          // times writing resumed in a new file after a fault
  int last_errno = 0;                    // of the last failed call; 0 for a short write
  DiskOp last_op = DiskOp::kNone;
  bool writing = true;  // false from a fault until a new file is open again

  // "disk full (write: No space left on device)", "I/O error (fsync: Input/output error)", ...
  std::string reason() const;
};

class LogFileSet {
 public:
  // Told the fate of every event given to write(), by the caller's tag (the disk thread).
  class Listener {
   public:
    virtual void written(std::uint32_t tag, std::size_t payload_bytes) noexcept = 0;
    virtual void lost(std::uint32_t tag) noexcept = 0;

   protected:
    ~Listener() = default;
  };

  static constexpr double kRetryInterval_s = 1.0;
  static constexpr std::size_t kBufferBytes = std::size_t{1} << 20;  // larger events are written on their own
  static constexpr std::size_t kMaxBufferedEvents = 16384;

  // Creates `dir` if needed, picks the recording's base name from `start_time` and opens
  // the first file. Throws std::runtime_error naming the path if it cannot. `listener` may
  // be null; `io` must outlive the set.
  LogFileSet(const std::filesystem::path& dir, const std::string& file_prefix, RotationPolicy policy,
             std::time_t start_time, double now_s, Listener* listener = nullptr, LogFileIo& io = posix_log_file_io());
  ~LogFileSet();
  LogFileSet(const LogFileSet&) = delete;
  LogFileSet& operator=(const LogFileSet&) = delete;

  // Takes one event, rotating first if a limit says so. `now_s` is a monotonic time [s].
  // True if it was taken (its fate is told to the listener later); false if it was lost at
  // once (closed, or waiting to retry after a fault; the listener has been told).
  bool write(const char* channel, std::size_t channel_length, const void* data, std::size_t size, std::int64_t utime,
             double now_s, std::uint32_t tag = 0) noexcept;

  // An event to write first in each file opened from now on (the keyed rig's marker,
  // record/record_auth.hpp), stamped with the time of the event that follows it. The listener
  // is not told about it, nor is it counted as lost. Call before the first write().
  void set_file_header(std::string channel, std::vector<std::uint8_t> data);

  // Hands the buffered events to the kernel (a crash then loses at most one flush interval).
  void flush() noexcept;
  // Flushes, fsyncs and closes the current file (removed if it holds no event); write()
  // afterwards opens no new one.
  void close() noexcept;

  // "<dir>/<file_prefix>hystloop-YYYYmmdd-HHMMSS" (the summary goes to base + ".summary.json").
  const std::filesystem::path& base_path() const noexcept { return base_; }
  // Files so far (removed ones not listed); the disk thread changes it, so call after
  // close() or from the disk thread.
  const std::vector<LogFileInfo>& files() const noexcept { return files_; }
  // Any thread.
  std::filesystem::path current_file() const;
  std::size_t file_count() const;
  DiskFaults faults() const noexcept;

  // The bytes an event occupies in the file (LCM's framing: magic, number, time, lengths).
  static std::uint64_t event_bytes(std::size_t channel_length, std::size_t size) noexcept {
    return kEventHeaderBytes + channel_length + size;
  }

 private:
  static constexpr std::size_t kEventHeaderBytes = 28;
  static constexpr std::uint32_t kFileHeaderTag = UINT32_MAX;
  struct Buffered {
    std::uint32_t end;  // offset in buffer_ just past the event
    std::uint32_t tag;
    std::uint32_t payload_bytes;
  };

  bool open_next(double now_s) noexcept;
  void close_current() noexcept;
  bool flush_buffer() noexcept;
  bool write_direct(const char* channel, std::size_t channel_length, const void* data, std::size_t size,
                    std::int64_t utime, std::uint32_t tag) noexcept;
  std::size_t write_all(const void* data, std::size_t size, int& error) noexcept;
  void buffer_event(const char* channel, std::size_t channel_length, const void* data, std::size_t size,
                    std::int64_t utime, std::uint32_t tag) noexcept;
  void frame(std::uint8_t* at, std::size_t channel_length, std::size_t size, std::int64_t utime) noexcept;
  void commit(std::uint32_t tag, std::uint64_t bytes, std::size_t payload_bytes) noexcept;
  void lose(std::uint32_t tag) noexcept;
  void fault(DiskOp op, int error) noexcept;
  void cut_back() noexcept;

  LogFileIo& io_;
  Listener* listener_;
  std::filesystem::path base_;
  RotationPolicy policy_;
  int fd_ = -1;
  std::unique_ptr<std::uint8_t[]> buffer_;
  std::unique_ptr<Buffered[]> buffered_;
  std::size_t buffer_used_ = 0;
  std::size_t buffered_count_ = 0;
  std::uint64_t file_events_taken_ = 0;  // in the current file, buffered ones included (the next event number)
  std::uint64_t file_bytes_taken_ = 0;
  std::vector<LogFileInfo> files_;
  std::string header_channel_;
  std::vector<std::uint8_t> header_data_;
  double now_s_ = 0.0;  // the latest time write() was given
  double opened_s_ = 0.0;
  double retry_at_s_ = 0.0;
  bool closed_ = false;
  mutable std::mutex names_mutex_;  // guards files_' growth and shrinking against current_file()

  std::atomic<std::uint64_t> errors_{0};
  std::atomic<std::uint64_t> events_lost_{0};
  std::atomic<std::uint64_t> files_truncated_{0};
  std::atomic<std::uint64_t> files_removed_{0};
  std::atomic<std::uint64_t> unconfirmed_events_{0};
  std::atomic<std::uint64_t> recoveries_{0};
  std::atomic<int> last_errno_{0};
  std::atomic<DiskOp> last_op_{DiskOp::kNone};
  std::atomic<bool> writing_{true};
};

}  // namespace hystloop
