#include "logger/log_file_set.hpp"

#include <cerrno>
#include <cstring>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <system_error>
#include <utility>

#include <spdlog/fmt/chrono.h>
#include <spdlog/fmt/fmt.h>

namespace hystloop {

namespace {
constexpr std::uint32_t kEventMagic = 0xEDA1DA01u;  // LCM's event log framing (lcm/eventlog.c)

std::string recording_name(const std::string& file_prefix, std::time_t start_time) {
  std::tm local{};
  localtime_r(&start_time, &local);
  return fmt::format("{}hystloop-{:%Y%m%d-%H%M%S}", file_prefix, local);
}

std::filesystem::path numbered(const std::filesystem::path& base, std::size_t index) {
  return fmt::format("{}.{:03}.lcmlog", base.string(), index);
}

std::uint8_t* put_be(std::uint8_t* at, std::uint64_t value, int bytes) noexcept {
  for (int i = bytes - 1; i >= 0; --i) *at++ = static_cast<std::uint8_t>(value >> (8 * i));
  return at;
}

std::string error_text(int error) { return std::error_code(error, std::generic_category()).message(); }

const char* op_name(DiskOp op) noexcept {
  constexpr const char* kNames[] = {"none", "create", "write", "truncate", "fsync", "close"};  // by DiskOp
  static_assert(std::size(kNames) == static_cast<std::size_t>(DiskOp::kClose) + 1);
  return kNames[static_cast<std::size_t>(op)];
}
}  // namespace

std::string DiskFaults::reason() const {
  if (last_op == DiskOp::kNone) return "no disk fault";
  const std::string kind = last_errno == ENOSPC || last_errno == EDQUOT ? "disk full"
                           : last_errno == 0                            ? "short write"
                           : last_errno == EIO                          ? "I/O error"
                                                                        : "disk error";
  const std::string text = last_errno == 0 ? "the kernel took fewer bytes than given" : error_text(last_errno);
  return kind + " (" + op_name(last_op) + ": " + text + ")";
}

LogFileSet::LogFileSet(const std::filesystem::path& dir, const std::string& file_prefix, RotationPolicy policy,
                       std::time_t start_time, double now_s, Listener* listener, LogFileIo& io)
    : io_(io),
      listener_(listener),
      policy_(policy),
      buffer_(new std::uint8_t[kBufferBytes]),
      buffered_(new Buffered[kMaxBufferedEvents]),
      now_s_(now_s),
      retry_at_s_(-std::numeric_limits<double>::infinity()) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create the log directory " + dir.string() + ": " + ec.message());
  const std::string name = recording_name(file_prefix, start_time);
  base_ = dir / name;
  for (int n = 1;
       std::filesystem::exists(numbered(base_, 0)) || std::filesystem::exists(base_.string() + ".summary.json"); ++n) {
    base_ = dir / (name + "-" + std::to_string(n));
  }
  files_.reserve(256);
  if (!open_next(now_s)) {
    throw std::runtime_error("cannot open the log file " + numbered(base_, 0).string() + ": " +
                             error_text(last_errno_.load()));
  }
}

LogFileSet::~LogFileSet() { close(); }

bool LogFileSet::open_next(double now_s) noexcept {
  try {
    const std::filesystem::path path = numbered(base_, files_.size());
    const int fd = io_.create(path.c_str());
    if (fd < 0) {
      fault(DiskOp::kCreate, -fd);
      return false;
    }
    try {
      const std::lock_guard lock(names_mutex_);
      files_.push_back(LogFileInfo{path, 0, 0});
    } catch (...) {
      io_.close(fd);
      io_.remove(path.c_str());
      throw;
    }
    fd_ = fd;
  } catch (...) {  // path building or the (rare) vector growth failed
    fault(DiskOp::kCreate, ENOMEM);
    return false;
  }
  opened_s_ = now_s;
  file_events_taken_ = 0;
  file_bytes_taken_ = 0;
  return true;
}

void LogFileSet::fault(DiskOp op, int error) noexcept {
  errors_.fetch_add(1, std::memory_order_relaxed);
  last_errno_.store(error, std::memory_order_relaxed);
  last_op_.store(op, std::memory_order_relaxed);
  writing_.store(false, std::memory_order_release);
  retry_at_s_ = now_s_ + kRetryInterval_s;
}

void LogFileSet::commit(std::uint32_t tag, std::uint64_t bytes, std::size_t payload_bytes) noexcept {
  LogFileInfo& file = files_.back();
  ++file.events;
  file.bytes += bytes;
  if (!writing_.load(std::memory_order_relaxed)) {
    writing_.store(true, std::memory_order_release);
    recoveries_.fetch_add(1, std::memory_order_relaxed);
  }
  if (listener_ != nullptr && tag != kFileHeaderTag) listener_->written(tag, payload_bytes);
}

void LogFileSet::lose(std::uint32_t tag) noexcept {
  if (tag == kFileHeaderTag) return;  // not an event of the record
  events_lost_.fetch_add(1, std::memory_order_relaxed);
  if (listener_ != nullptr) listener_->lost(tag);
}

std::size_t LogFileSet::write_all(const void* data, std::size_t size, int& error) noexcept {
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  std::size_t done = 0;
  error = 0;
  while (done < size) {
    const ssize_t rc = io_.write(fd_, bytes + done, size - done);
    if (rc < 0) {
      error = static_cast<int>(-rc);
      break;
    }
    if (rc == 0) break;  // a short write without an error: counted as one
    done += static_cast<std::size_t>(rc) < size - done ? static_cast<std::size_t>(rc) : size - done;
  }
  return done;
}

// After a failed write: the file must end at its last complete event, so every reader
// reads it to the end; then it is closed (and removed if that leaves it empty).
void LogFileSet::cut_back() noexcept {
  const int rc = io_.truncate(fd_, files_.back().bytes);
  if (rc < 0) {
    fault(DiskOp::kTruncate, -rc);
  } else {
    files_truncated_.fetch_add(1, std::memory_order_relaxed);
  }
}

void LogFileSet::close_current() noexcept {
  if (fd_ < 0) return;
  if (!flush_buffer()) return;  // the fault closed it
  LogFileInfo& file = files_.back();
  bool confirmed = true;
  if (file.events > 0) {
    if (const int rc = io_.fsync(fd_); rc < 0) {
      fault(DiskOp::kFsync, -rc);
      confirmed = false;
    }
  }
  if (const int rc = io_.close(fd_); rc < 0) {
    fault(DiskOp::kClose, -rc);
    confirmed = false;
  }
  fd_ = -1;
  if (!confirmed) unconfirmed_events_.fetch_add(file.events, std::memory_order_relaxed);
  if (file.events == 0) {
    io_.remove(file.path.c_str());
    const std::lock_guard lock(names_mutex_);
    files_.pop_back();
    files_removed_.fetch_add(1, std::memory_order_relaxed);
  }
}

bool LogFileSet::flush_buffer() noexcept {
  if (buffer_used_ == 0) return true;
  int error = 0;
  const std::size_t done = write_all(buffer_.get(), buffer_used_, error);
  std::size_t start = 0;
  std::size_t complete = 0;  // bytes of the events the kernel took whole
  for (std::size_t i = 0; i < buffered_count_; ++i) {
    const Buffered& event = buffered_[i];
    if (event.end <= done) {
      commit(event.tag, event.end - start, event.payload_bytes);
      complete = event.end;
    } else {
      lose(event.tag);
    }
    start = event.end;
  }
  const bool ok = done == buffer_used_;
  buffer_used_ = 0;
  buffered_count_ = 0;
  if (!ok) {
    fault(DiskOp::kWrite, error);
    if (done > complete) cut_back();
    close_current();  // buffer empty now: fsync, close, remove if empty
  }
  return ok;
}

void LogFileSet::frame(std::uint8_t* at, std::size_t channel_length, std::size_t size, std::int64_t utime) noexcept {
  at = put_be(at, kEventMagic, 4);
  at = put_be(at, file_events_taken_, 8);
  at = put_be(at, static_cast<std::uint64_t>(utime), 8);
  at = put_be(at, channel_length, 4);
  put_be(at, size, 4);
}

bool LogFileSet::write_direct(const char* channel, std::size_t channel_length, const void* data, std::size_t size,
                              std::int64_t utime, std::uint32_t tag) noexcept {
  std::uint8_t header[kEventHeaderBytes];
  frame(header, channel_length, size, utime);
  int error = 0;
  std::size_t done = write_all(header, sizeof header, error);
  if (done == sizeof header) done += write_all(channel, channel_length, error);
  if (done == sizeof header + channel_length) done += write_all(data, size, error);
  if (done == event_bytes(channel_length, size)) {
    ++file_events_taken_;
    file_bytes_taken_ += done;
    commit(tag, done, size);
    return true;
  }
  lose(tag);
  fault(DiskOp::kWrite, error);
  if (done > 0) cut_back();
  close_current();
  return false;
}

bool LogFileSet::write(const char* channel, std::size_t channel_length, const void* data, std::size_t size,
                       std::int64_t utime, double now_s, std::uint32_t tag) noexcept {
  if (closed_ || channel_length > static_cast<std::size_t>(INT32_MAX) || size > static_cast<std::size_t>(INT32_MAX)) {
    lose(tag);
    return false;
  }
  now_s_ = now_s;
  const std::uint64_t bytes = event_bytes(channel_length, size);
  if (fd_ >= 0 && file_events_taken_ > 0) {
    const bool too_big = policy_.max_file_bytes > 0 && file_bytes_taken_ + bytes > policy_.max_file_bytes;
    const bool too_old = policy_.max_file_s > 0 && now_s - opened_s_ >= policy_.max_file_s;
    if (too_big || too_old) close_current();
  }
  // After a fault, nothing for kRetryInterval_s (each refused event is counted), then a new file.
  // An event larger than the buffer is written on its own, after what the buffer holds.
  if (fd_ < 0 && (now_s < retry_at_s_ || !open_next(now_s))) {
    lose(tag);
    return false;
  }
  // A new file's buffer is empty, so the header always fits.
  if (file_events_taken_ == 0 && !header_data_.empty()) {
    buffer_event(header_channel_.data(), header_channel_.size(), header_data_.data(), header_data_.size(), utime,
                 kFileHeaderTag);
  }
  const bool direct = bytes > kBufferBytes;
  const bool full = direct || buffer_used_ + bytes > kBufferBytes || buffered_count_ == kMaxBufferedEvents;
  if (full && !flush_buffer()) {
    lose(tag);
    return false;
  }
  if (direct) return write_direct(channel, channel_length, data, size, utime, tag);
  buffer_event(channel, channel_length, data, size, utime, tag);
  return true;
}

void LogFileSet::buffer_event(const char* channel, std::size_t channel_length, const void* data, std::size_t size,
                              std::int64_t utime, std::uint32_t tag) noexcept {
  const std::uint64_t bytes = event_bytes(channel_length, size);
  std::uint8_t* at = buffer_.get() + buffer_used_;
  frame(at, channel_length, size, utime);
  std::memcpy(at + kEventHeaderBytes, channel, channel_length);
  if (size > 0) std::memcpy(at + kEventHeaderBytes + channel_length, data, size);
  buffer_used_ += bytes;
  buffered_[buffered_count_++] =
      Buffered{static_cast<std::uint32_t>(buffer_used_), tag, static_cast<std::uint32_t>(size)};
  ++file_events_taken_;
  file_bytes_taken_ += bytes;
}

void LogFileSet::set_file_header(std::string channel, std::vector<std::uint8_t> data) {
  header_channel_ = std::move(channel);
  header_data_ = std::move(data);
}

void LogFileSet::flush() noexcept {
  if (fd_ >= 0) flush_buffer();
}

void LogFileSet::close() noexcept {
  close_current();
  closed_ = true;
}

std::filesystem::path LogFileSet::current_file() const {
  const std::lock_guard lock(names_mutex_);
  return files_.empty() ? std::filesystem::path{} : files_.back().path;
}

std::size_t LogFileSet::file_count() const {
  const std::lock_guard lock(names_mutex_);
  return files_.size();
}

DiskFaults LogFileSet::faults() const noexcept {
  DiskFaults f;
  f.errors = errors_.load(std::memory_order_relaxed);
  f.events_lost = events_lost_.load(std::memory_order_relaxed);
  f.files_truncated = files_truncated_.load(std::memory_order_relaxed);
  f.files_removed = files_removed_.load(std::memory_order_relaxed);
  f.unconfirmed_events = unconfirmed_events_.load(std::memory_order_relaxed);
  f.recoveries = recoveries_.load(std::memory_order_relaxed);
  f.last_errno = last_errno_.load(std::memory_order_relaxed);
  f.last_op = last_op_.load(std::memory_order_relaxed);
  f.writing = writing_.load(std::memory_order_acquire);
  return f;
}

}  // namespace hystloop
