#include "logger/logger_service.hpp"

#include <chrono>
#include <climits>
#include <csignal>
#include <ctime>
#include <string>

#include <spdlog/spdlog.h>

#include "core/process.hpp"
#include "lcm/connection.hpp"
#include "lcm/message_storage.hpp"
#include "lcm/wire_layout.hpp"
#include "runtime/io_loop.hpp"

namespace hystloop {

namespace {
double monotonic_s() noexcept {
  using namespace std::chrono;
  return duration<double>(steady_clock::now().time_since_epoch()).count();
}

std::int64_t monotonic_ns() noexcept {
  using namespace std::chrono;
  return duration_cast<nanoseconds>(steady_clock::now().time_since_epoch()).count();
}

// Decodes a block as a Subscription would (fingerprint, length fields walked before decode
// trusts them, the whole buffer used) but without the value check: a block's ticks count for
// gap detection whatever its values. False if it is not a block of that type with >= 1 tick.
template <class Block>
bool decode_block(Block& block, const void* data, std::size_t size) noexcept {
  if (size < 8 || size > static_cast<std::size_t>(INT_MAX)) return false;
  if (wire_fingerprint(data, size) != Block::getHash()) return false;
  if (walk_wire_layout(wire_layout_of<Block>(), data, size) != static_cast<std::int64_t>(size)) return false;
  clear_arrays(block);
  int used = -1;
  try {
    used = block.decode(data, 0, static_cast<int>(size));
  } catch (...) {  // cannot happen within the reserved storage; never let it reach LCM
    return false;
  }
  return used == static_cast<int>(size) && block.n_ticks >= 1;
}

std::string append(std::string detail, const std::string& what) {
  return detail.empty() ? what : detail + "; " + what;
}
}  // namespace

LoggerService::LoggerService(lcm::LCM& lcm, const ChannelNames& names, const LoggerOptions& options)
    : lcm_(lcm),
      options_(options),
      channels_regex_(options.channels.empty() ? names.all_channels_regex() : options.channels),
      start_utime_(wall_utime()),
      start_s_(monotonic_s()),
      reporter_(lcm, names.status, kProcessName) {
  channels_ = std::make_unique<ChannelTable>(names.sensor, names.command, options.restart_threshold,
                                             static_cast<std::int64_t>(options.command_resume_s * 1e6));
  reserve_storage(sensor_block_);
  reserve_storage(command_block_);
  ring_ = std::make_unique<RecordRing>(static_cast<std::size_t>(options.queue_mb * 1e6));
  const RotationPolicy policy{static_cast<std::uint64_t>(options.max_file_mb * 1e6), options.max_file_s};
  files_ = std::make_unique<LogFileSet>(options.out_dir, options.file_prefix, policy, std::time(nullptr), start_s_);
  writer_ = std::make_unique<LogWriter>(*ring_, *channels_, *files_, options.flush_interval_s);
  writer_->start();

  raw_ = lcm_subscribe(lcm_.getUnderlyingLCM(), channels_regex_.c_str(), &LoggerService::on_raw, this);
  if (raw_ == nullptr) throw std::runtime_error("LCM could not subscribe to " + channels_regex_);
  // LCM's default of 30 queued messages is 1.5 ms at 2 x 10 kHz.
  lcm_subscription_set_queue_capacity(raw_, static_cast<int>(options.lcm_queue));

  Subscription<control_t>::Options control_options;
  control_options.queue_capacity = 64;
  control_ = std::make_unique<Subscription<control_t>>(
      lcm_, names.control, [this](const control_t& msg, std::int64_t) { on_control(msg); }, control_options);
}

LoggerService::~LoggerService() {
  unsubscribe();
  if (writer_) writer_->stop();
}

void LoggerService::on_raw(const lcm_recv_buf_t* rbuf, const char* channel, void* self) noexcept {
  static_cast<LoggerService*>(self)->receive(channel, rbuf->data, rbuf->data_size, rbuf->recv_utime);
}

void LoggerService::receive(const char* channel, const void* data, std::size_t size,
                            std::int64_t recv_utime) noexcept {
  const std::int64_t t0 = monotonic_ns();
  const auto index = channels_->find_or_add(channel);
  if (!index) return;  // counted by the table
  ChannelSlot& slot = (*channels_)[*index];
  ++slot.received;
  slot.bytes_received += size;
  if (slot.kind != SequenceKind::kNone) check_sequence(slot, data, size, recv_utime);
  switch (ring_->try_push(*index, recv_utime, data, size)) {
    case RecordRing::PushResult::kOk: break;
    case RecordRing::PushResult::kFull: ++slot.dropped_queue_full; break;
    case RecordRing::PushResult::kTooLarge: ++slot.dropped_oversize; break;
  }
  handling_.add(monotonic_ns() - t0);
}

void LoggerService::check_sequence(ChannelSlot& slot, const void* data, std::size_t size,
                                   std::int64_t recv_utime) noexcept {
  std::int64_t first = 0;
  std::int64_t n_ticks = 0;
  if (slot.kind == SequenceKind::kSensor && decode_block(sensor_block_, data, size)) {
    first = sensor_block_.seq;
    n_ticks = sensor_block_.n_ticks;
  } else if (slot.kind == SequenceKind::kCommand && decode_block(command_block_, data, size)) {
    first = command_block_.seq;
    n_ticks = command_block_.n_ticks;
  } else {
    ++slot.undecodable;
    return;
  }
  slot.sequence.observe(first, n_ticks, recv_utime);
}

void LoggerService::on_control(const control_t& msg) {
  if (!control_filter_.accept(msg)) return;
  if (msg.command == control_t::SHUTDOWN) {
    spdlog::info("SHUTDOWN requested (request {})", msg.request_id);
    shutdown_requested_ = true;
    request_stop();
  } else if (msg.command == control_t::RESET_COUNTERS) {
    spdlog::info("RESET_COUNTERS ignored: the logger's counters describe the whole recording (see the summary)");
  }
}

void LoggerService::report(std::int64_t utime, std::int8_t state_override) {
  std::string detail;
  std::uint64_t bytes_written = 0;
  for (std::size_t i = 0; i < channels_->size(); ++i) {
    const ChannelSlot& c = (*channels_)[i];
    const SequenceGapDetector& q = c.sequence;
    const Seen now{c.dropped(), q.gap_events(), q.missing(), q.overlaps() + q.duplicates(), q.resumes(), q.skipped()};
    Seen& before = seen_[i];
    const std::string on = " on " + std::string(c.name_view());
    if (now.dropped > before.dropped) detail = append(detail, "dropped " + std::to_string(now.dropped - before.dropped) + on);
    if (now.gap_events > before.gap_events) {
      detail = append(detail, std::to_string(now.gap_events - before.gap_events) + " gap(s), " +
                                  std::to_string(now.missing - before.missing) + " ticks missing" + on);
    }
    if (now.overlaps > before.overlaps) {
      detail = append(detail, std::to_string(now.overlaps - before.overlaps) + " overlapping/duplicate block(s)" + on);
    }
    if (now.resumes > before.resumes) {
      detail = append(detail, std::to_string(now.resumes - before.resumes) + " resume(s) after silence, " +
                                  std::to_string(now.skipped - before.skipped) + " ticks skipped" + on);
    }
    before = now;
    bytes_written += c.bytes_written.load(std::memory_order_relaxed);
  }
  const std::uint64_t unrecorded = channels_->unrecorded_channels();
  if (unrecorded > seen_unrecorded_) {
    detail = append(detail, "dropped " + std::to_string(unrecorded - seen_unrecorded_) + " of channels beyond the table's " +
                                std::to_string(ChannelTable::kMaxChannels));
  }
  seen_unrecorded_ = unrecorded;

  std::int8_t state = detail.empty() ? service_status_t::HEALTHY : service_status_t::DEGRADED;
  if (state_override >= 0) state = state_override;
  if (state == service_status_t::DEGRADED) detail += " (file " + files_->current_file().filename().string() + ")";
  reporter_.begin(state, detail);
  for (std::size_t i = 0; i < channels_->size(); ++i) {
    const ChannelSlot& c = (*channels_)[i];
    const std::string name(c.name_view());
    reporter_.counter(name + ".received", c.received);
    reporter_.counter(name + ".written", c.written.load(std::memory_order_relaxed));
    reporter_.counter(name + ".dropped", c.dropped());
    if (c.kind != SequenceKind::kNone) {
      const SequenceGapDetector& q = c.sequence;
      reporter_.counter(name + ".gaps", q.gap_events());
      reporter_.counter(name + ".missing", q.missing());
      reporter_.counter(name + ".overlaps", q.overlaps());
      reporter_.counter(name + ".duplicates", q.duplicates());
      reporter_.counter(name + ".out_of_order", q.out_of_order());
      reporter_.counter(name + ".restarts", q.restarts());
      reporter_.counter(name + ".undecodable", c.undecodable);
      if (c.kind == SequenceKind::kCommand) {
        reporter_.counter(name + ".resumes", q.resumes());
        reporter_.counter(name + ".skipped", q.skipped());
      }
    }
  }
  reporter_.counter("files", files_->file_count());
  reporter_.counter("bytes_written", bytes_written);
  reporter_.counter("events_written", writer_->events_written());
  reporter_.counter("queue_used_bytes", ring_->used_bytes());
  reporter_.counter("queue_high_water_bytes", writer_->queue_high_water_bytes());
  reporter_.counter("unrecorded_channel", unrecorded);
  reporter_.endpoint("control", control_->counters());
  reporter_.loop_timing(handling_);
  handling_.reset();
  reporter_.publish(utime);
}

void LoggerService::unsubscribe() noexcept {
  if (raw_ != nullptr) lcm_unsubscribe(lcm_.getUnderlyingLCM(), raw_);
  raw_ = nullptr;
}

int LoggerService::run() {
  spdlog::info("recording '{}' to {}.NNN.lcmlog", channels_regex_, files_->base_path().string());
  report(wall_utime());  // at once: tells a waiting publisher the logger is listening
  const int lcm_errors = run_io_loop(lcm_, IoLoopOptions{}, [this](std::int64_t utime) { report(utime); });
  if (lcm_errors > 0) spdlog::warn("LCM reported {} errors while receiving", lcm_errors);

  const RecordingSummary summary = finish();
  for (const std::string& line : summary_lines(summary, *channels_)) spdlog::info("{}", line);
  const std::filesystem::path path = options_.summary_file.empty()
                                         ? std::filesystem::path(files_->base_path().string() + ".summary.json")
                                         : options_.summary_file;
  int rc = 0;
  try {
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
    write_file_atomically(path, summary_json(summary, *channels_));
    spdlog::info("summary written to {}", path.string());
  } catch (const std::exception& e) {
    spdlog::error("summary not written: {}", e.what());
    rc = 1;
  }
  report(wall_utime(), service_status_t::STOPPING);
  return rc;
}

RecordingSummary LoggerService::finish() {
  // Take what LCM already holds (the sender may have finished just before the signal),
  // until the network has been quiet for 20 ms or 0.5 s have passed.
  const double until_s = monotonic_s() + 0.5;
  while (monotonic_s() < until_s && handle_pending(lcm_, std::chrono::microseconds(20000)) > 0) {
  }
  unsubscribe();
  writer_->stop();

  RecordingSummary s;
  s.recording = files_->base_path().string();
  s.start_utime = start_utime_;
  s.stop_utime = wall_utime();
  s.duration_s = monotonic_s() - start_s_;
  const int signal = stop_signal();
  s.stop_reason = shutdown_requested_  ? "control SHUTDOWN"
                  : signal == SIGTERM  ? "SIGTERM"
                  : signal == SIGINT   ? "SIGINT"
                  : signal != 0        ? "signal " + std::to_string(signal)
                                       : "stop request";
  s.files = files_->files();
  s.unrecorded_channel = channels_->unrecorded_channels();
  s.queue_capacity_bytes = ring_->capacity_bytes();
  s.queue_high_water_bytes = writer_->queue_high_water_bytes();
  const ResourceUsage usage = read_resource_usage();
  s.cpu_user_s = usage.user_cpu_s;
  s.cpu_system_s = usage.system_cpu_s;
  s.peak_rss_bytes = usage.peak_rss_bytes;
  return s;
}

}  // namespace hystloop
