#pragma once
// hystloop-bridge's I/O thread: owns lcm::LCM. Publishes the ticks the real-time thread
// queues as HX_SENSOR blocks of bridge.block_ticks, receives HX_COMMAND blocks into the
// real-time thread's queue (measuring block-to-answer latency), acts on HX_CONTROL (ARM,
// DISARM, SET_GAINS, RESET_COUNTERS, SHUTDOWN), and reports HX_STATUS at 1 Hz.

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

#include <lcm/lcm-cpp.hpp>

#include "bridge/bridge_realtime.hpp"
#include "bridge/bridge_settings.hpp"
#include "core/clock.hpp"
#include "core/latency_stats.hpp"
#include "core/log_limiter.hpp"
#include "core/send_time_ring.hpp"
#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/sim_truth_t.hpp"
#include "lcm/channels.hpp"
#include "lcm/control_filter.hpp"
#include "lcm/publisher.hpp"
#include "lcm/sensor_block_repair.hpp"
#include "lcm/subscription.hpp"
#include "runtime/control_acks.hpp"
#include "runtime/counter_set.hpp"
#include "runtime/status_reporter.hpp"

namespace hystloop {

class BridgeService {
 public:
  BridgeService(const BridgeSettings& settings, lcm::LCM& lcm, const ChannelNames& channels);

  // Runs until SIGINT/SIGTERM, a SHUTDOWN request or bridge.run_seconds; then ramps the
  // actuator to actuator.safe_u_V (still publishing the samples), stops the real-time thread,
  // publishes what it still holds and a last status. Returns 0, or 1 if LCM reported errors or
  // the ramp did not end within stop_ramp_timeout_s (the longest ramp + kStopRampMargin_s).
  int run();

  // At exit, also write the summary's figures as JSON to `path` (empty: don't).
  void write_summary_to(std::string path) { summary_json_path_ = std::move(path); }

 private:
  void on_command(const command_block_t& msg) noexcept;
  void on_control(const control_t& msg);
  // Count the request, tell its sender and log "<what> (request <id>)" (act: unless `what` is null).
  void act(const control_t& msg, const char* what);
  void refuse(const control_t& msg, const std::string& what, std::string why);
  void publish_samples(bool flush) noexcept;
  void publish_block() noexcept;
  void append_truth(const OutgoingTick& t) noexcept;
  void publish_truth() noexcept;
  void serve(bool stopping);  // one pass of the I/O loop: samples out, LCM in, status
  CounterSet::Entries counter_entries(const RtReport& rt) const;
  void report(const RtReport& rt, std::int64_t utime, bool stopping);
  // Disarmed, and every axis at its actuator.safe_u_V.
  bool at_safe_voltage(const RtReport& rt) const noexcept;
  void log_safe_stop(const SafeStopResult& safe) const;
  void summarize(const RtReport& rt, const SafeStopResult& safe) const;

  BridgeSettings settings_;
  lcm::LCM& lcm_;
  BridgeRealtime rt_;
  Publisher<sensor_block_t> sensor_pub_;
  sensor_block_t block_{};  // being filled; storage reserved
  // A simulated stage's true position for the same ticks, published after block_ (none on hardware).
  std::optional<Publisher<sim_truth_t>> truth_pub_;
  sim_truth_t truth_{};
  std::uint64_t truth_unpublished_ = 0;  // blocks the Publisher refused
  Subscription<command_block_t> commands_;
  Subscription<control_t> control_;
  ControlFilter filter_{"bridge"};
  StatusReporter status_;
  SendTimeRing sent_;
  LatencyStats latency_;        // sensor block sent -> the command block answering it received, this period
  LatencyStats latency_total_;  // since start, for the summary

  // I/O-thread counters (cumulative).
  std::uint64_t command_queue_full_ = 0;
  std::uint64_t control_acted_ = 0;
  std::uint64_t control_refused_ = 0;
  ControlAcks acks_;  // what was done with the last requests, for their senders
  std::uint64_t command_blocks_ = 0;
  std::uint64_t command_blocks_wrong_axes_ = 0;  // planned for another number of axes: refused whole
  std::uint64_t sensor_blocks_ = 0;
  // Sensor blocks whose values the contract refuses are published repaired (sensor_block_repair.hpp):
  std::uint64_t sensor_blocks_repaired_ = 0;
  std::uint64_t sensor_ticks_repaired_ = 0;
  std::uint64_t sensor_blocks_unpublished_ = 0;  // ... and any the Publisher still refused (a hole: logged)
  std::uint64_t sensor_ticks_unpublished_ = 0;
  SensorBlockRepair repair_;
  LogLimiter log_limiter_;  // one line a second per reason (LogReason)
  enum LogReason : std::size_t { kLogSensorRepaired, kLogSensorUnpublished };
  std::array<FeedbackGains, kMaxAxes> gains_;  // each axis's servo, as last set
  std::string summary_json_path_;
  double started_s_ = monotonic_s();  // [s], core/clock.hpp

  // I/O loop state.
  std::chrono::steady_clock::time_point next_report_{};
  bool awaiting_report_ = false;
  bool stopping_ = false;  // ramping to the safe voltage: ARM refused
  int lcm_errors_ = 0;

  // Report bookkeeping.
  std::string safe_reason_ = "not armed";
  std::uint64_t stall_trips_reported_ = 0;  // RtReport::stall_trips when last reported
  std::uint64_t position_trips_reported_ = 0;
  std::uint64_t oscillation_trips_reported_ = 0;
  std::uint64_t previous_skipped_ = 0;  // RtReport::ticks_skipped at the last report
  std::uint64_t trips_reported_ = 0;
  BridgeCounters previous_core_{};
  std::uint64_t previous_dropped_ = 0;
  std::uint64_t previous_repaired_ = 0;     // sensor_ticks_repaired_ at the last report
  std::uint64_t previous_unpublished_ = 0;  // sensor_ticks_unpublished_ at the last report
  bool reset_pending_ = false;
  CounterSet counters_;
  // Why the buffer may have run dry (watchdog_reason): the last command block pushed, and the
  // I/O thread's longest pass and wait in the report period, monotonic [ns].
  std::int64_t last_command_ns_ = -1;
  std::int64_t last_pass_end_ns_ = -1;
  std::int64_t longest_pass_ns_ = 0;
  std::int64_t longest_wait_ns_ = 0;
  std::int64_t last_report_ns_ = monotonic_ns();
  std::uint64_t previous_command_rejected_ = 0;
  std::uint64_t previous_queue_full_ = 0;
};

}  // namespace hystloop
