#include "logger/logger_service.hpp"

#include <chrono>
#include <climits>
#include <csignal>
#include <ctime>
#include <string>
#include <string_view>

#include <spdlog/spdlog.h>

#include "core/clock.hpp"
#include "core/errors.hpp"
#include "core/escape.hpp"
#include "core/process.hpp"
#include "core/saturating.hpp"
#include "lcm/connection.hpp"
#include "runtime/summary_file.hpp"
#include "lcm/message_storage.hpp"
#include "lcm/wire_layout.hpp"
#include "record/record_auth.hpp"
#include "runtime/io_loop.hpp"

namespace hystloop {

namespace {
// Decodes a block as a Subscription would (fingerprint, length fields walked before decode
// trusts them, the whole buffer used) but without the value check: a block's ticks count for
// gap detection whatever its values. False if it is not a block of that type with >= 1 tick.
template <class Block>
bool decode_block(Block& block, const void* data, std::size_t size) noexcept {
  if (size < 8 || size > static_cast<std::size_t>(INT_MAX)) return false;
  if (wire_fingerprint(data, size) != Block::getHash()) return false;
  const std::int64_t body = lcm_body_size(wire_layout_of<Block>(), data, size);  // a signed block's trailer ignored
  if (body < 0) return false;
  clear_arrays(block);
  int used = -1;
  try {
    used = block.decode(data, 0, static_cast<int>(body));
  } catch (...) {  // cannot happen within the reserved storage; never let it reach LCM
    return false;
  }
  return used == static_cast<int>(body) && block.n_ticks >= 1;
}

// "870 unsigned, 2 bad_mac": a channel's refusals by reason.
std::string refused_reasons(const ChannelSlot& c) {
  std::string out;
  for (std::size_t r = 1; r < kAuthResults; ++r) {
    if (c.refused[r] == 0) continue;
    out += fmt::format("{}{} {}", out.empty() ? "" : ", ", c.refused[r], to_string(static_cast<AuthResult>(r)));
  }
  return out;
}

std::string append(std::string detail, const std::string& what) {
  if (what.empty()) return detail;
  return detail.empty() ? what : detail + "; " + what;
}
}  // namespace

LoggerService::LoggerService(lcm::LCM& lcm, const ChannelNames& names, const LoggerOptions& options,
                             const std::shared_ptr<const RigAuth>& auth)
    : lcm_(lcm),
      options_(options),
      channels_regex_(options.channels.empty() ? names.all_channels_regex() : options.channels),
      start_utime_(wall_utime()),
      start_s_(monotonic_s()),
      reporter_(lcm, names.status, kProcessName) {
  // First, before anything is created on disk: LCM refuses a regular expression it cannot
  // compile (no message is dispatched before run()).
  raw_ = lcm_subscribe(lcm_.getUnderlyingLCM(), channels_regex_.c_str(), &LoggerService::on_raw, this);
  if (raw_ == nullptr) {
    throw ParameterError("logger.channels", "LCM refuses '" + escape_wire(channels_regex_, kEscapeUncut) +
                                                "' (not a regular expression it can compile)");
  }
  try {
    // LCM's default of 30 queued messages is 1.5 ms at 2 x 10 kHz.
    lcm_subscription_set_queue_capacity(raw_, static_cast<int>(options.lcm_queue));
    channels_ = std::make_unique<ChannelTable>(names, options.restart_threshold,
                                               static_cast<std::int64_t>(options.command_resume_s * 1e6));
    write_counter_ = std::make_unique<ChannelWriteCounter>(*channels_);
    reserve_storage(sensor_block_);
    reserve_storage(command_block_);
    ring_ = std::make_unique<RecordRing>(static_cast<std::size_t>(options.queue_mb * 1e6));
    const RotationPolicy policy{static_cast<std::uint64_t>(options.max_file_mb * 1e6), options.max_file_s};
    files_ = std::make_unique<LogFileSet>(options.out_dir, options.file_prefix, policy, std::time(nullptr), start_s_,
                                          write_counter_.get());
    if (auth != nullptr) {
      keyed_ = true;
      for (std::size_t i = 0; i < ChannelTable::kRigChannels; ++i) {
        ChannelSlot& slot = (*channels_)[i];
        if (!is_authenticated_channel(slot.name_view())) continue;
        // Nothing signed before the logger started is recorded, as no service takes it.
        verifiers_[i] = std::make_unique<MessageVerifier>(auth->key, auth->max_skew_us, start_utime_);
        slot.verified = true;
      }
      files_->set_file_header(channel_name(names.prefix, kRecordSuffix), keyed_record_marker(start_utime_));
    }
    writer_ = std::make_unique<LogWriter>(*ring_, *channels_, *files_, options.flush_interval_s);
    writer_->start();

    control_ = std::make_unique<Subscription<control_t>>(
        lcm_, names.control, [this](const control_t& msg, std::int64_t) { on_control(msg); },
        Subscription<control_t>::Options{.queue_capacity = 64, .on_reject = {}, .auth = auth});
  } catch (...) {
    unsubscribe();
    if (writer_) writer_->stop();
    throw;
  }
}

LoggerService::~LoggerService() {
  unsubscribe();
  if (writer_) writer_->stop();
}

void LoggerService::on_raw(const lcm_recv_buf_t* rbuf, const char* channel, void* self) noexcept {
  static_cast<LoggerService*>(self)->receive(channel, rbuf->data, rbuf->data_size, rbuf->recv_utime);
}

void LoggerService::receive(const char* channel, const void* data, std::size_t size, std::int64_t recv_utime) noexcept {
  const std::int64_t t0 = monotonic_ns();
  const auto index = channels_->find_or_add(channel);
  if (!index) return;  // counted by the table
  ChannelSlot& slot = (*channels_)[*index];
  ++slot.received;
  slot.bytes_received += size;
  if (*index < verifiers_.size() && verifiers_[*index] != nullptr) {
    // What every service refuses stays out of the record and out of the gap arithmetic.
    const AuthResult result = verify_recorded(*verifiers_[*index], slot.name_view(), data, size, recv_utime);
    if (result != AuthResult::kOk) {
      ++slot.refused[static_cast<std::size_t>(result)];
      handling_.add(monotonic_ns() - t0);
      return;
    }
  }
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
  const auto observe = [&](const auto& block) { slot.sequence.observe(block.seq, block.n_ticks, recv_utime); };
  if (slot.kind == SequenceKind::kSensor && decode_block(sensor_block_, data, size)) {
    observe(sensor_block_);
  } else if (slot.kind == SequenceKind::kCommand && decode_block(command_block_, data, size)) {
    observe(command_block_);
  } else {
    ++slot.undecodable;
  }
}

void LoggerService::on_control(const control_t& msg) {
  if (!control_filter_.accept(msg)) return;
  if (msg.command == control_t::SHUTDOWN) {
    acks_.acted(msg.request_id);
    spdlog::info("SHUTDOWN requested (request {})", msg.request_id);
    shutdown_requested_ = true;
    request_stop();
  } else if (msg.command == control_t::RESET_COUNTERS) {
    // Sent to every process, it is answered as done (there is nothing to reset here); asked of
    // the logger by name, it is refused, so the sender learns that these counters do not reset.
    if (msg.target.empty()) {
      acks_.acted(msg.request_id);
    } else {
      acks_.refused(msg.request_id, "the logger's counters describe the whole recording: they do not reset",
                    wall_utime());
    }
    // Anyone can send these: at most one line every 10 s, saying how many were not logged.
    if (const LogLimiter::Gate g = slow_log_.allow(kLogResetIgnored, monotonic_ns())) {
      spdlog::info("RESET_COUNTERS ignored: the logger's counters describe the whole recording (see the summary){}",
                   suppressed_note(g));
    }
  }
}

void LoggerService::on_tick(std::int64_t utime) {
  // A disk fault (or the recovery from one) is reported at once, the rest once a second.
  const DiskFaults f = files_->faults();
  const bool disk_news = f.errors != seen_faults_.errors || f.writing != seen_faults_.writing;
  if (disk_news || acks_.due() || utime - last_report_utime_ >= 1000000) report(utime);
}

std::string LoggerService::fault_detail(const DiskFaults& f) {
  std::string detail;
  const std::string file = escape_wire(files_->current_file().filename().string());
  if (!f.writing || f.errors > seen_faults_.errors) {
    detail = fmt::format("FAULT: {}; {} events not written so far", f.reason(), f.events_lost);
    if (!f.writing) detail += fmt::format(", retrying in a new file every {} s", LogFileSet::kRetryInterval_s);
  } else if (!seen_faults_.writing) {
    detail = fmt::format("recovered from the disk fault: writing again to {} after {} events not written", file,
                         f.events_lost);
  }
  if (!seen_faults_.writing && f.writing && f.recoveries > seen_faults_.recoveries) {
    spdlog::warn("disk: writing again to {} ({} events not written during the fault)", file, f.events_lost);
  } else if (seen_faults_.writing && !f.writing) {
    // Once per fault: the retries that follow are counted, not logged.
    spdlog::error("disk fault: {}; events are counted as dropped until a new file can be written (retried every {} s)",
                  f.reason(), LogFileSet::kRetryInterval_s);
  } else if (f.errors > seen_faults_.errors && f.writing) {
    spdlog::error("disk fault: {} (writing continues)", f.reason());
  }
  seen_faults_ = f;
  return detail;
}

std::string LoggerService::unknown_channels_detail() {
  const UnknownChannels& u = channels_->unknown();
  if (u.messages() <= seen_unrecorded_) return {};
  std::string names;
  for (std::size_t i = 0; i < u.kept_count(); ++i) names += (i ? ", '" : "'") + escape_wire(u.kept_name(i)) + "'";
  std::string detail = fmt::format("not recorded: {} message(s) on {}{} channel(s) beyond the table's {} (first: {})",
                                   u.messages() - seen_unrecorded_, u.distinct_is_lower_bound() ? ">= " : "",
                                   u.distinct(), ChannelTable::kMaxChannels, names);
  if (u.distinct() > seen_unknown_names_) {
    if (const LogLimiter::Gate g = slow_log_.allow(kLogUnknownChannels, monotonic_ns())) {
      spdlog::warn("{}{}", detail, suppressed_note(g));
    }
  }
  seen_unrecorded_ = u.messages();
  seen_unknown_names_ = u.distinct();
  return detail;
}

void LoggerService::report(std::int64_t utime, std::int8_t state_override) {
  last_report_utime_ = utime;
  const DiskFaults faults = files_->faults();
  std::string detail = fault_detail(faults);
  std::uint64_t bytes_written = 0;
  std::uint64_t dropped = 0;
  std::uint64_t refused_total = 0;
  std::uint64_t other_channels = 0, other_received = 0, other_written = 0, other_dropped = 0;
  for (std::size_t i = 0; i < channels_->size(); ++i) {
    const ChannelSlot& c = (*channels_)[i];
    // Counts fed by the wire: every sum saturates rather than wrap to a plausible small number.
    add_saturating(bytes_written, c.bytes_written.load(std::memory_order_relaxed));
    add_saturating(dropped, c.dropped());
    add_saturating(refused_total, c.refused_total());
    if (!c.rig) {  // names off the wire: summed, never put in the detail one by one
      ++other_channels;
      add_saturating(other_received, c.received);
      add_saturating(other_written, c.written.load(std::memory_order_relaxed));
      add_saturating(other_dropped, c.dropped());
      continue;
    }
    const SequenceGapDetector& q = c.sequence;
    const std::uint64_t overlaps = saturating_add(q.overlaps(), q.duplicates());
    const Seen now{c.dropped(), q.gap_events(), q.missing(),    overlaps,
                   q.resumes(), q.skipped(),    q.violations(), c.refused_total()};
    Seen& before = seen_[i];
    const std::string_view name = c.name_view();
    // What went wrong on the channel since the last report: "<what> on <channel>".
    const auto say = [&](bool news, const std::string& what) {
      if (news) detail = append(detail, fmt::format("{} on {}", what, name));
    };
    say(now.dropped > before.dropped, fmt::format("dropped {}", now.dropped - before.dropped));
    say(now.gap_events > before.gap_events,
        fmt::format("{} gap(s), {} ticks missing", now.gap_events - before.gap_events, now.missing - before.missing));
    say(now.overlaps > before.overlaps,
        fmt::format("{} overlapping/duplicate block(s)", now.overlaps - before.overlaps));
    say(now.resumes > before.resumes, fmt::format("{} resume(s) after silence, {} ticks skipped",
                                                  now.resumes - before.resumes, now.skipped - before.skipped));
    say(now.violations > before.violations,
        fmt::format("{} block(s) breaking the channel contract (seq or n_ticks out of range; not checked for gaps)",
                    now.violations - before.violations));
    if (now.refused > before.refused) {
      const std::string what = fmt::format("refused {} message(s) whose signature failed ({}; not recorded)",
                                           now.refused - before.refused, refused_reasons(c));
      say(true, what);
      if (const LogLimiter::Gate g = slow_log_.allow(kLogRefused, monotonic_ns())) {
        spdlog::warn("{} on {}{}", what, name, suppressed_note(g));
      }
    }
    before = now;
  }
  if (other_dropped > seen_other_dropped_) {
    detail = append(detail, "dropped " + std::to_string(other_dropped - seen_other_dropped_) + " on other channels");
  }
  seen_other_dropped_ = other_dropped;
  const std::uint64_t unrecorded = channels_->unrecorded_channels();
  detail = append(detail, unknown_channels_detail());

  std::int8_t state = detail.empty() ? service_status_t::HEALTHY : service_status_t::DEGRADED;
  if (state_override >= 0) state = state_override;
  if (state == service_status_t::DEGRADED) {
    detail += " (file " + escape_wire(files_->current_file().filename().string()) + ")";
  }
  if (const std::string note = acks_.refusal_note(utime); !note.empty()) detail = append(detail, note);
  reporter_.begin(state, detail);
  acks_.report(reporter_);
  for (std::size_t i = 0; i < ChannelTable::kRigChannels; ++i) {
    const ChannelSlot& c = (*channels_)[i];
    const std::string name(c.name_view());
    reporter_.counter(name + ".received", c.received);
    reporter_.counter(name + ".written", c.written.load(std::memory_order_relaxed));
    reporter_.counter(name + ".dropped", c.dropped());
    if (c.verified) {
      for (std::size_t r = 1; r < kAuthResults; ++r) {
        reporter_.counter(name + ".rejected_" + std::string(to_string(static_cast<AuthResult>(r))), c.refused[r]);
      }
    }
    if (c.kind != SequenceKind::kNone) {
      const SequenceGapDetector& q = c.sequence;
      reporter_.counter(name + ".gaps", q.gap_events());
      reporter_.counter(name + ".missing", q.missing());
      reporter_.counter(name + ".overlaps", q.overlaps());
      reporter_.counter(name + ".duplicates", q.duplicates());
      reporter_.counter(name + ".out_of_order", q.out_of_order());
      reporter_.counter(name + ".restarts", q.restarts());
      reporter_.counter(name + ".undecodable", c.undecodable);
      for (std::size_t v = 0; v < SequenceGapDetector::kViolationKinds; ++v) {
        const auto reason = static_cast<SequenceGapDetector::Violation>(v);
        reporter_.counter(name + ".contract_" + SequenceGapDetector::to_string(reason), q.violations(reason));
      }
      if (c.kind == SequenceKind::kCommand) {
        reporter_.counter(name + ".resumes", q.resumes());
        reporter_.counter(name + ".skipped", q.skipped());
      }
    }
  }
  reporter_.counter("other_channels", other_channels);
  reporter_.counter("other.received", other_received);
  reporter_.counter("other.written", other_written);
  reporter_.counter("other.dropped", other_dropped);
  reporter_.counter("files", files_->file_count());
  reporter_.counter("bytes_written", bytes_written);
  reporter_.counter("events_written", write_counter_->events_written());
  reporter_.counter("dropped", saturating_add(dropped, unrecorded));
  reporter_.counter("disk_errors", faults.errors);
  reporter_.counter("disk_events_lost", faults.events_lost);
  reporter_.counter("disk_files_truncated", faults.files_truncated);
  reporter_.counter("disk_files_removed", faults.files_removed);
  reporter_.counter("disk_unconfirmed_events", faults.unconfirmed_events);
  reporter_.counter("queue_used_bytes", ring_->used_bytes());
  reporter_.counter("queue_high_water_bytes", writer_->queue_high_water_bytes());
  reporter_.counter("unrecorded_channel", unrecorded);
  reporter_.counter("keyed", keyed_ ? 1 : 0);
  reporter_.counter("rejected_auth", refused_total);
  reporter_.counter("unknown_channel_names", channels_->unknown().distinct());
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
  IoLoopOptions loop;
  loop.period = std::chrono::milliseconds(100);  // on_tick reports a disk fault within 0.1 s
  const int lcm_errors = run_io_loop(lcm_, loop, [this](std::int64_t utime) { on_tick(utime); });
  if (lcm_errors > 0) spdlog::warn("LCM reported {} errors while receiving", lcm_errors);

  const RecordingSummary summary = finish();
  // After a disk fault (its line "DISK FAULT: ..." among them) they are errors: the exit status is 1.
  const auto level = summary.disk.errors > 0 ? spdlog::level::err : spdlog::level::info;
  for (const std::string& line : summary_lines(summary, *channels_)) spdlog::log(level, "{}", line);
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
  if (summary.disk.errors > 0) rc = 1;
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
  s.stop_reason = shutdown_requested_ ? "control SHUTDOWN"
                  : signal == SIGTERM ? "SIGTERM"
                  : signal == SIGINT  ? "SIGINT"
                  : signal != 0       ? "signal " + std::to_string(signal)
                                      : "stop request";
  s.files = files_->files();
  s.disk = files_->faults();
  s.unrecorded_channel = channels_->unrecorded_channels();
  s.keyed = keyed_;
  s.queue_capacity_bytes = ring_->capacity_bytes();
  s.queue_high_water_bytes = writer_->queue_high_water_bytes();
  const ResourceUsage usage = read_resource_usage();
  s.cpu_user_s = usage.user_cpu_s;
  s.cpu_system_s = usage.system_cpu_s;
  s.peak_rss_bytes = usage.peak_rss_bytes;
  return s;
}

}  // namespace hystloop
