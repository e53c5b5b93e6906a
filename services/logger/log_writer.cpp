#include "logger/log_writer.hpp"

#include <pthread.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "core/clock.hpp"
#include "core/errors.hpp"

namespace hystloop {

void ChannelWriteCounter::written(std::uint32_t tag, std::size_t payload_bytes) noexcept {
  ChannelSlot& slot = channels_[tag];
  slot.written.fetch_add(1, std::memory_order_relaxed);
  slot.bytes_written.fetch_add(payload_bytes, std::memory_order_relaxed);
  written_.fetch_add(1, std::memory_order_relaxed);
}

void ChannelWriteCounter::lost(std::uint32_t tag) noexcept {
  channels_[tag].write_failed.fetch_add(1, std::memory_order_relaxed);
}

LogWriter::LogWriter(RecordRing& ring, const ChannelTable& channels, LogFileSet& files, double flush_interval_s)
    : ring_(ring), channels_(channels), files_(files), flush_interval_s_(flush_interval_s) {
  require_positive("flush_interval_s", flush_interval_s);
}

LogWriter::~LogWriter() { stop(); }

void LogWriter::start() {
  if (thread_.joinable()) return;
  thread_ = std::thread([this] { run(); });
  pthread_setname_np(thread_.native_handle(), "logger-disk");
}

void LogWriter::stop() {
  stopping_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
  files_.close();
}

void LogWriter::run() noexcept {
  // The writer wakes on a timer, not per record: the loop's channels bring ~1,000 messages a
  // second, so waking per record (a notify from the receive thread) costs as many wake-ups as a
  // fixed 1 ms doze did (919 a second, ~1 % of a core). It dozes as long as the ring can hold
  // what arrives meanwhile, at the rate of the last round, with a quarter of it to spare:
  // kMaxDoze_s with the default 64 MB, shorter for a small --queue-mb under a heavy stream.
  constexpr double kMaxDoze_s = 0.02, kMinDoze_s = 0.001, kRingShare = 0.25;
  constexpr std::size_t kBatch = 4096;
  double last_flush_s = monotonic_s();
  double last_round_s = last_flush_s;
  for (;;) {
    // Read the flag before draining: whatever was queued before stop() is then written.
    const bool last_round = stopping_.load(std::memory_order_acquire);
    const std::uint64_t used = ring_.used_bytes();
    if (used > high_water_.load(std::memory_order_relaxed)) high_water_.store(used, std::memory_order_relaxed);
    const double now_s = monotonic_s();
    std::size_t n = 0, bytes = 0;
    do {
      n = ring_.drain(
          [&](const RecordRing::Record& r) noexcept {
            bytes += r.size;
            const ChannelSlot& slot = channels_[r.channel];  // the tag: the channel's index
            files_.write(slot.name.data(), slot.name_length, r.data, r.size, r.recv_utime, now_s, r.channel);
          },
          kBatch);
    } while (n > 0 && last_round);
    if (last_round) break;
    if (now_s - last_flush_s >= flush_interval_s_) {
      files_.flush();
      last_flush_s = now_s;
    }
    if (n == kBatch) continue;  // more may be waiting
    const double rate_B_per_s = static_cast<double>(bytes) / std::max(now_s - last_round_s, 1e-4);
    last_round_s = now_s;
    const double fits_s = kRingShare * static_cast<double>(ring_.capacity_bytes()) / std::max(rate_B_per_s, 1.0);
    std::this_thread::sleep_for(std::chrono::duration<double>(std::clamp(fits_s, kMinDoze_s, kMaxDoze_s)));
  }
  files_.flush();
}

}  // namespace hystloop
