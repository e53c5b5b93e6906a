#pragma once
// hystloop-bridge's I/O thread: owns lcm::LCM. Publishes the samples the real-time thread
// queues (HX_SENSOR), receives HX_COMMAND into the real-time thread's queue (measuring
// sample-to-command latency), acts on HX_CONTROL (ARM, DISARM, RESET_COUNTERS, SHUTDOWN),
// and reports HX_STATUS at 1 Hz.

#include <cstdint>
#include <memory>
#include <string>

#include <lcm/lcm-cpp.hpp>

#include "bridge/bridge_realtime.hpp"
#include "bridge/bridge_settings.hpp"
#include "bridge/send_time_ring.hpp"
#include "core/latency_stats.hpp"
#include "hystloop/actuator_command_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/sensor_sample_t.hpp"
#include "lcm/channels.hpp"
#include "lcm/publisher.hpp"
#include "lcm/subscription.hpp"
#include "runtime/control_filter.hpp"
#include "runtime/status_reporter.hpp"

namespace hystloop {

class BridgeService {
 public:
  BridgeService(const BridgeSettings& settings, lcm::LCM& lcm, const ChannelNames& channels);

  // Runs until SIGINT/SIGTERM, a SHUTDOWN request or bridge.run_seconds; then stops the
  // real-time thread, publishes what it still holds and a last status. Returns 0, or 1 if
  // LCM reported errors.
  int run();

 private:
  void on_command(const actuator_command_t& msg) noexcept;
  void on_control(const control_t& msg);
  void publish_samples() noexcept;
  void report(const RtReport& rt, std::int64_t utime, bool stopping);
  void log_summary(const RtReport& rt) const;

  BridgeSettings settings_;
  lcm::LCM& lcm_;
  BridgeRealtime rt_;
  Publisher<sensor_sample_t> sensor_pub_;
  sensor_sample_t sample_msg_{};
  Subscription<actuator_command_t> commands_;
  Subscription<control_t> control_;
  ControlFilter filter_{"bridge"};
  StatusReporter status_;
  SendTimeRing sent_;
  LatencyStats latency_;  // sample sent -> its command received, this report period
  LatencyStats latency_total_;  // since start, for the summary

  // I/O-thread counters (cumulative).
  std::uint64_t command_queue_full_ = 0;
  std::uint64_t control_acted_ = 0;
  std::uint64_t control_refused_ = 0;

  // Report bookkeeping.
  std::string safe_reason_ = "not armed";
  std::uint64_t trips_reported_ = 0;
  BridgeCounters previous_core_{};
  std::uint64_t previous_dropped_ = 0;
  bool reset_pending_ = false;
  struct Baseline {
    BridgeCounters core{};
    std::uint64_t skipped = 0, dropped = 0, queue_full = 0, acted = 0, refused = 0;
    EndpointCounters commands{}, control{};
    PublisherCounters sensor{};
  } baseline_;
};

}  // namespace hystloop
