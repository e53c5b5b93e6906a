#include "logger/log_file_set.hpp"

#include <lcm/eventlog.h>
#include <unistd.h>

#include <cinttypes>
#include <ctime>
#include <stdexcept>
#include <system_error>

namespace hystloop {

namespace {
constexpr std::size_t kStdioBufferBytes = std::size_t{1} << 20;

std::string recording_name(const std::string& file_prefix, std::time_t start_time) {
  std::tm local{};
  localtime_r(&start_time, &local);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", &local);
  return file_prefix + "hystloop-" + stamp;
}

std::filesystem::path numbered(const std::filesystem::path& base, std::size_t index) {
  char suffix[32];
  std::snprintf(suffix, sizeof suffix, ".%03zu.lcmlog", index);
  return base.string() + suffix;
}
}  // namespace

LogFileSet::LogFileSet(std::filesystem::path dir, std::string file_prefix, RotationPolicy policy,
                       std::time_t start_time, double now_s)
    : policy_(policy), stdio_buffer_(new char[kStdioBufferBytes]) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create the log directory " + dir.string() + ": " + ec.message());
  const std::string name = recording_name(file_prefix, start_time);
  base_ = dir / name;
  for (int n = 1; std::filesystem::exists(numbered(base_, 0)) ||
                  std::filesystem::exists(base_.string() + ".summary.json");
       ++n) {
    base_ = dir / (name + "-" + std::to_string(n));
  }
  files_.reserve(256);
  if (!open_next(now_s)) throw std::runtime_error("cannot open the log file " + numbered(base_, 0).string());
}

LogFileSet::~LogFileSet() { close(); }

bool LogFileSet::open_next(double now_s) noexcept {
  last_open_attempt_s_ = now_s;
  try {
    const std::filesystem::path path = numbered(base_, files_.size());
    log_ = lcm_eventlog_create(path.c_str(), "w");
    if (log_ == nullptr) {
      ++open_failures_;
      return false;
    }
    // Large writes: the disk sees a few big writes per second instead of one per message.
    std::setvbuf(log_->f, stdio_buffer_.get(), _IOFBF, kStdioBufferBytes);
    const std::lock_guard lock(names_mutex_);
    files_.push_back(LogFileInfo{path, 0, 0});
  } catch (...) {  // path building or the (rare) vector growth failed
    if (log_ != nullptr) lcm_eventlog_destroy(log_);
    log_ = nullptr;
    ++open_failures_;
    return false;
  }
  opened_s_ = now_s;
  return true;
}

void LogFileSet::close_current() noexcept {
  if (log_ == nullptr) return;
  std::fflush(log_->f);
  ::fsync(fileno(log_->f));
  lcm_eventlog_destroy(log_);  // fclose: the stdio buffer is free again after this
  log_ = nullptr;
}

bool LogFileSet::write(const char* channel, std::size_t channel_length, const void* data, std::size_t size,
                       std::int64_t utime, double now_s) noexcept {
  if (closed_) return false;
  const std::uint64_t bytes = event_bytes(channel_length, size);
  if (log_ != nullptr && files_.back().events > 0) {
    const bool too_big = policy_.max_file_bytes > 0 && files_.back().bytes + bytes > policy_.max_file_bytes;
    const bool too_old = policy_.max_file_s > 0 && now_s - opened_s_ >= policy_.max_file_s;
    if (too_big || too_old) {
      close_current();
      if (!open_next(now_s)) return false;
    }
  }
  // After a failed open, retry at most once a second (each refused event is counted).
  if (log_ == nullptr && (now_s - last_open_attempt_s_ < 1.0 || !open_next(now_s))) return false;

  lcm_eventlog_event_t event{};
  event.timestamp = utime;
  event.channellen = static_cast<std::int32_t>(channel_length);
  event.datalen = static_cast<std::int32_t>(size);
  event.channel = const_cast<char*>(channel);  // LCM's struct is not const-correct; it only reads
  event.data = const_cast<void*>(data);
  if (lcm_eventlog_write_event(log_, &event) != 0) return false;
  LogFileInfo& file = files_.back();
  ++file.events;
  file.bytes += bytes;
  return true;
}

void LogFileSet::flush() noexcept {
  if (log_ != nullptr) std::fflush(log_->f);
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

}  // namespace hystloop
