#pragma once
// hystloop-logger's wiring: one raw LCM subscription to the rig's channels (every message
// recorded byte-exact, whatever its type) -> RecordRing -> LogWriter (disk thread) ->
// LogFileSet. The receive path (LCM's handler, in the thread that calls run()) looks up
// the channel in a fixed table, checks the ticks of the HX_SENSOR/HX_COMMAND blocks for
// gaps by decoding into messages reserved for MAX_VALUES, and copies the bytes into the
// ring: no allocation, no lock, no log, no disk. A full ring drops the message and counts
// it per channel.
//
// HX_STATUS (process "logger") once a second, and at once when the disk fails or recovers:
// per rig channel received/written/dropped, and for the two block channels gaps/missing
// (ticks)/overlaps/duplicates/out_of_order/restarts/contract_<reason> (+ resumes/skipped for
// HX_COMMAND, see SequenceGapDetector); other recorded channels summed under "other.*";
// channels without a slot as unrecorded_channel (messages) and unknown_channel_names; files,
// bytes, dropped and the disk faults (disk_errors, disk_events_lost, ...; see LogFileSet).
// On a keyed rig, per signed rig channel rejected_<reason> (unsigned, malformed, bad_mac,
// replayed, skewed: messages not recorded), and rejected_auth in all.
// DEGRADED with a detail when something was dropped or refused, a gap, overlap, resume or
// contract violation seen in the last period. A disk fault is DEGRADED with a detail starting "FAULT: "
// and the reason ("FAULT: disk full (write: No space left on device); ...") for as long as
// nothing can be written (service_status_t has no FAULT state; DEGRADED + this prefix needs no
// type change).
// On SIGINT/SIGTERM or a control_t SHUTDOWN for "logger": receive what LCM already holds,
// stop receiving, write the queue out, close the file, write the summary (logger_summary.hpp).

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include <lcm/lcm-cpp.hpp>

#include "core/latency_stats.hpp"
#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "lcm/channels.hpp"
#include "core/log_limiter.hpp"
#include "lcm/control_filter.hpp"
#include "lcm/subscription.hpp"
#include "logger/log_file_set.hpp"
#include "logger/log_writer.hpp"
#include "logger/logger_options.hpp"
#include "logger/logger_summary.hpp"
#include "record/channel_table.hpp"
#include "record/record_ring.hpp"
#include "runtime/control_acks.hpp"
#include "runtime/status_reporter.hpp"

namespace hystloop {

class LoggerService {
 public:
  static constexpr const char* kProcessName = "logger";

  // Subscribes and opens the first log file. Throws ParameterError (logger.channels not a
  // regular expression LCM accepts) / std::runtime_error. With `auth` (a keyed rig) the rig's
  // signed channels are verified as the services verify them: what fails is counted by reason,
  // not recorded; each file starts with the keyed marker (record/record_auth.hpp).
  LoggerService(lcm::LCM& lcm, const ChannelNames& names, const LoggerOptions& options,
                const std::shared_ptr<const RigAuth>& auth = process_rig_auth());
  ~LoggerService();
  LoggerService(const LoggerService&) = delete;
  LoggerService& operator=(const LoggerService&) = delete;

  // Records until a stop is requested, then closes and writes the summary.
  // Returns 0, or 1 if a disk fault lost events (or left some unconfirmed) or the summary
  // could not be written.
  int run();

  const ChannelTable& channels() const noexcept { return *channels_; }

 private:
  static void on_raw(const lcm_recv_buf_t* rbuf, const char* channel, void* self) noexcept;
  void receive(const char* channel, const void* data, std::size_t size, std::int64_t recv_utime) noexcept;
  void check_sequence(ChannelSlot& slot, const void* data, std::size_t size, std::int64_t recv_utime) noexcept;
  void on_control(const control_t& msg);
  void on_tick(std::int64_t utime);
  void report(std::int64_t utime, std::int8_t state_override = -1);
  std::string fault_detail(const DiskFaults& faults);
  std::string unknown_channels_detail();
  void unsubscribe() noexcept;
  RecordingSummary finish();

  lcm::LCM& lcm_;
  LoggerOptions options_;
  std::string channels_regex_;
  std::int64_t start_utime_;
  double start_s_;

  std::unique_ptr<ChannelTable> channels_;
  std::unique_ptr<ChannelWriteCounter> write_counter_;
  std::unique_ptr<RecordRing> ring_;
  std::unique_ptr<LogFileSet> files_;
  std::unique_ptr<LogWriter> writer_;
  // The rig's signed channels' verifiers, by slot (null: not verified); one per channel, as one
  // Subscription per channel in the services. Made before the first message, never after.
  std::array<std::unique_ptr<MessageVerifier>, ChannelTable::kRigChannels> verifiers_;
  bool keyed_ = false;
  lcm_subscription_t* raw_ = nullptr;
  sensor_block_t sensor_block_{};  // storage reserved for MAX_VALUES (MAX_TICKS of MAX_AXES)
  command_block_t command_block_{};

  ControlFilter control_filter_{kProcessName};
  ControlAcks acks_;  // what was done with the last requests, for their senders
  std::unique_ptr<Subscription<control_t>> control_;
  bool shutdown_requested_ = false;
  StatusReporter reporter_;
  LatencyStats handling_;  // time spent on one received message [ns]

  // What the last report had seen, to tell whether anything went wrong in this period.
  struct Seen {
    std::uint64_t dropped = 0;
    std::uint64_t gap_events = 0;
    std::uint64_t missing = 0;
    std::uint64_t overlaps = 0;  // overlapping and duplicate blocks
    std::uint64_t resumes = 0;
    std::uint64_t skipped = 0;
    std::uint64_t violations = 0;  // blocks breaking the channel contract, all reasons
    std::uint64_t refused = 0;     // signatures that failed
  };
  std::array<Seen, ChannelTable::kMaxChannels> seen_{};
  std::uint64_t seen_other_dropped_ = 0;
  std::uint64_t seen_unrecorded_ = 0;
  std::uint64_t seen_unknown_names_ = 0;
  DiskFaults seen_faults_{};
  std::int64_t last_report_utime_ = 0;
  // Unknown channels and ignored RESET_COUNTERS (anyone can send them) are logged at most every 10 s.
  enum LogReason : std::size_t { kLogUnknownChannels, kLogResetIgnored, kLogRefused };
  LogLimiter slow_log_{10'000'000'000};
};

}  // namespace hystloop
