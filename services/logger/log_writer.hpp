#pragma once
// The disk thread: takes records out of the RecordRing and writes them to the LogFileSet,
// flushing every `flush_interval_s`. It is the only thread that touches the files, so a
// slow disk stalls nothing but this thread; the ring absorbs the backlog meanwhile.
// stop() lets it write everything already queued, then closes the file.

#include <atomic>
#include <cstdint>
#include <thread>

#include "record/channel_table.hpp"
#include "logger/log_file_set.hpp"
#include "record/record_ring.hpp"

namespace hystloop {

// Where the fate of every event goes: its channel's written/bytes_written or write_failed
// (tags are ChannelTable indices), and the total written. Called by the disk thread.
class ChannelWriteCounter final : public LogFileSet::Listener {
 public:
  explicit ChannelWriteCounter(ChannelTable& channels) : channels_(channels) {}
  void written(std::uint32_t tag, std::size_t payload_bytes) noexcept override;
  void lost(std::uint32_t tag) noexcept override;
  std::uint64_t events_written() const noexcept { return written_.load(std::memory_order_relaxed); }

 private:
  ChannelTable& channels_;
  std::atomic<std::uint64_t> written_{0};
};

class LogWriter {
 public:
  // Both must outlive the writer; `files` tags each event with its ChannelTable index (give
  // it a ChannelWriteCounter to count them). flush_interval_s > 0.
  LogWriter(RecordRing& ring, const ChannelTable& channels, LogFileSet& files, double flush_interval_s);
  ~LogWriter();
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;

  void start();
  // Drains the ring, closes the files and joins the thread (idempotent).
  void stop();

  // Ring occupancy the writer has seen at most [bytes]: how close the disk came to losing data.
  std::uint64_t queue_high_water_bytes() const noexcept { return high_water_.load(std::memory_order_relaxed); }

 private:
  void run() noexcept;

  RecordRing& ring_;
  const ChannelTable& channels_;
  LogFileSet& files_;
  double flush_interval_s_;
  std::thread thread_;
  std::atomic<bool> stopping_{false};
  std::atomic<std::uint64_t> high_water_{0};
};

}  // namespace hystloop
