#pragma once
// The disk thread: takes records out of the RecordRing and writes them to the LogFileSet,
// flushing every `flush_interval_s`. It is the only thread that touches the files, so a
// slow disk stalls nothing but this thread; the ring absorbs the backlog meanwhile.
// stop() lets it write everything already queued, then closes the file.

#include <atomic>
#include <cstdint>
#include <thread>

#include "logger/channel_table.hpp"
#include "logger/log_file_set.hpp"
#include "logger/record_ring.hpp"

namespace hystloop {

class LogWriter {
 public:
  // All three must outlive the writer. flush_interval_s > 0.
  LogWriter(RecordRing& ring, ChannelTable& channels, LogFileSet& files, double flush_interval_s);
  ~LogWriter();
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;

  void start();
  // Drains the ring, closes the files and joins the thread (idempotent).
  void stop();

  std::uint64_t events_written() const noexcept { return written_.load(std::memory_order_relaxed); }
  // Ring occupancy the writer has seen at most [bytes]: how close the disk came to losing data.
  std::uint64_t queue_high_water_bytes() const noexcept { return high_water_.load(std::memory_order_relaxed); }

 private:
  void run() noexcept;
  void write_record(const RecordRing::Record& record, double now_s) noexcept;

  RecordRing& ring_;
  ChannelTable& channels_;
  LogFileSet& files_;
  double flush_interval_s_;
  std::thread thread_;
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> written_{0};
  std::atomic<std::uint64_t> high_water_{0};
};

}  // namespace hystloop
