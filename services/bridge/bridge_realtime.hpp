#pragma once
// The bridge's real-time thread: at each tick of the 10 kHz clock it takes the commands
// the I/O thread received, lets BridgeCore decide the voltage for tick k, steps the
// backend, and hands the sample back to the I/O thread (waking it through an eventfd).
// Nothing here allocates, locks, logs or does I/O other than that eventfd write.

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <thread>

#include "bridge/bridge_settings.hpp"
#include "bridge/rt_report.hpp"
#include "bridge/stage_backend.hpp"
#include "core/process.hpp"
#include "loop/bridge_core.hpp"
#include "loop/spsc_queue.hpp"

namespace hystloop {

struct IncomingCommand {
  std::int64_t seq = 0;
  double u_V = 0.0;
  std::int32_t params_version = 0;
};

struct OutgoingSample {
  std::int64_t seq = 0;
  std::int64_t utime = 0;  // wall time of the sample [us]
  double u_V = 0.0;
  double y_m = 0.0;
  std::int32_t flags = 0;
};

enum class ArmRequest : std::uint8_t { kNone = 0, kArm = 1, kDisarm = 2 };

class BridgeRealtime {
 public:
  static constexpr std::size_t kCommandQueue = 4096;  // 400 ms of commands
  static constexpr std::size_t kSampleQueue = 4096;

  BridgeRealtime(const BridgeSettings& settings, std::unique_ptr<StageBackend> backend);
  ~BridgeRealtime();
  BridgeRealtime(const BridgeRealtime&) = delete;
  BridgeRealtime& operator=(const BridgeRealtime&) = delete;

  // Starts the thread (scheduling set-up happens on it; see setup_status()).
  void start();
  // Asks the thread to stop after its current tick and joins it.
  void stop();

  // I/O thread side.
  bool push_command(const IncomingCommand& command) noexcept { return commands_.try_push(command); }
  std::optional<OutgoingSample> pop_sample() noexcept { return samples_.try_pop(); }
  void request_arm(ArmRequest request) noexcept { arm_request_.store(request, std::memory_order_release); }
  RtReportExchange& reports() noexcept { return reports_; }
  int wake_fd() const noexcept { return wake_fd_; }  // readable when samples are queued
  bool started() const noexcept { return started_.load(std::memory_order_acquire); }
  // What the real-time set-up did (valid once started()).
  const SetupStatus& priority_status() const noexcept { return priority_status_; }
  const SetupStatus& affinity_status() const noexcept { return affinity_status_; }
  const StageBackend& backend() const noexcept { return *backend_; }

 private:
  void run() noexcept;
  void tick(std::int64_t k, std::uint64_t skipped, std::int64_t lateness_ns) noexcept;

  BridgeSettings settings_;
  std::unique_ptr<StageBackend> backend_;
  BridgeCore core_;
  double dt_s_;
  SpscQueue<IncomingCommand, kCommandQueue> commands_;
  SpscQueue<OutgoingSample, kSampleQueue> samples_;
  std::atomic<ArmRequest> arm_request_{ArmRequest::kNone};
  RtReportExchange reports_;
  int wake_fd_ = -1;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> started_{false};
  SetupStatus priority_status_;
  SetupStatus affinity_status_;

  // RT-thread state.
  bool auto_arm_pending_ = false;
  bool tripped_ = false;  // in the safe state because of the watchdog (not an operator)
  std::uint64_t ticks_skipped_ = 0;
  std::uint64_t samples_dropped_ = 0;
  std::uint64_t commands_processed_ = 0;
  std::uint64_t auto_arms_ = 0;
  std::uint64_t trips_seen_ = 0;
  std::int64_t last_tick_ = -1;
  std::int64_t last_trip_tick_ = -1;
};

}  // namespace hystloop
