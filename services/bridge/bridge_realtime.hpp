#pragma once
// The bridge's real-time thread: at each tick of the 10 kHz clock it moves the commands the
// I/O thread received into the axes' jitter buffers, lets MultiAxisBridge decide every axis's
// voltage for tick k (per axis a BridgeCore: feedforward + servo, clamped; one safe state), steps
// the backend, and hands the tick to the I/O thread, waking it through an eventfd once a block is complete. With
// rt.ticks_per_wake > 1 it wakes once per that many ticks and runs them back to back (a simulator's choice). Nothing
// here allocates, locks, logs or does I/O other than that eventfd write.

#include <array>
#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <thread>

#include "bridge/bridge_settings.hpp"
#include "bridge/rt_report.hpp"
#include "bridge/servo_request.hpp"
#include "bridge/stage_backend.hpp"
#include "core/process.hpp"
#include "core/ticks.hpp"
#include "loop/arming_policy.hpp"
#include "loop/bridge_core.hpp"
#include "loop/multi_axis_bridge.hpp"
#include "loop/spsc_queue.hpp"

namespace hystloop {

// A tick the real-time thread did, every axis's, with the buffers' depth after it, for the I/O
// thread to publish in blocks.
struct OutgoingTick {
  std::array<SensorTick, kMaxAxes> ticks{};  // axis a's tick; the first `axes` are the stage's
  std::array<double, kMaxAxes> y_true_m{};   // StageReading::y_true_m per axis
  std::int32_t buffer_depth = 0;             // the axis with the fewest commands ahead
  std::int32_t axes = 1;
  const SensorTick& tick() const noexcept { return ticks[0]; }  // seq and utime: every axis's
};

// How the stop's ramp to actuator.safe_u_V went (BridgeRealtime::begin_safe_stop / stop).
struct SafeStopResult {
  bool requested = false;       // begin_safe_stop() was called
  bool reached = false;         // the ramp applied safe_u_V before the thread ended
  double u_start_V = 0.0;       // applied when the real-time thread took the request
  std::int64_t ramp_ticks = 0;  // ticks that moved the voltage (0: it was already safe)
  double ramp_s = 0.0;          // ramp_ticks * dt: loop time
  double wall_s = 0.0;          // from the request to the tick that applied safe_u_V (or to the timeout)
};

class BridgeRealtime {
 public:
  static constexpr std::size_t kCommandQueue = 16384;  // 1.6 s of commands
  static constexpr std::size_t kSampleQueue = 8192;

  BridgeRealtime(const BridgeSettings& settings, std::unique_ptr<StageBackend> backend);
  ~BridgeRealtime();
  BridgeRealtime(const BridgeRealtime&) = delete;
  BridgeRealtime& operator=(const BridgeRealtime&) = delete;

  // Starts the thread (scheduling set-up happens on it; see priority_status()/affinity_status()).
  void start();
  // The first half of every stop: from its next tick the thread disarms BridgeCore, refuses to
  // arm again and lets it ramp to actuator.safe_u_V (BridgeCore's safe state: min(ramp, slew)),
  // then tells the backend to hold_safe(). Idempotent; does not wait. I/O thread.
  void begin_safe_stop() noexcept;
  bool safe_reached() const noexcept { return safe_reached_.load(std::memory_order_acquire); }
  // Ends the thread, safely on every path (also from the destructor while an exception unwinds):
  // begins the safe stop if nobody did, waits until the ramp reached safe_u_V or
  // BridgeSettings::stop_ramp_timeout_s after the request passed, stops and joins the thread, then
  // calls backend.hold_safe(). Returns how the ramp went (also when called again).
  SafeStopResult stop();

  // I/O thread side. One tick's commands, one per axis (exactly axes() of them), taken together:
  // a tick is never commanded on some axes and not on others (false: the queue is full, or the
  // count is wrong; nothing taken).
  bool push_commands(std::span<const CommandTick> per_axis) noexcept;
  // A one-axis stage's command.
  bool push_command(const CommandTick& command) noexcept { return push_commands(std::span(&command, 1)); }
  // New servo gains for the axes `change` sets (validated by the caller), bumplessly, all on the
  // same tick (false: the queue is full; nothing taken).
  bool push_gains(const AxisGainsChange& change) noexcept { return gains_.try_push(change); }
  int axes() const noexcept { return stage_.axes(); }
  std::optional<OutgoingTick> pop_tick() noexcept { return samples_.try_pop(); }
  void request_arm(ArmRequest request) noexcept { arm_request_.store(request, std::memory_order_release); }
  RtReportExchange& reports() noexcept { return reports_; }
  int wake_fd() const noexcept { return wake_fd_; }  // readable when samples are queued
  bool started() const noexcept { return started_.load(std::memory_order_acquire); }
  // What the real-time set-up did (valid once started()).
  const SetupStatus& priority_status() const noexcept { return priority_status_; }
  const SetupStatus& affinity_status() const noexcept { return affinity_status_; }
  const StageBackend& backend() const noexcept { return *backend_; }
  // Each axis's safe voltage, axes() entries.
  std::span<const double> safe_voltages() const noexcept {
    return std::span(safe_u_V_).first(static_cast<std::size_t>(stage_.axes()));
  }

 private:
  void run() noexcept;
  // Runs tick k, started at start_ns (CLOCK_MONOTONIC); returns when it ended: the start of the
  // next tick of the same wake-up, so that a tick costs one clock read for its work figure, not two.
  std::int64_t tick(std::int64_t k, std::uint64_t skipped, std::int64_t start_ns) noexcept;

  BridgeSettings settings_;
  std::unique_ptr<StageBackend> backend_;
  MultiAxisBridge stage_;
  ArmingPolicy arming_;  // RT thread
  double dt_s_;
  struct TickCommands {
    std::array<CommandTick, kMaxAxes> axis{};
  };
  SpscQueue<TickCommands, kCommandQueue> commands_;  // a tick's commands of every axis
  SpscQueue<AxisGainsChange, 8> gains_;
  std::array<double, kMaxAxes> safe_u_V_{};  // each axis's actuator.safe_u_V
  SpscQueue<OutgoingTick, kSampleQueue> samples_;
  std::atomic<ArmRequest> arm_request_{ArmRequest::kNone};
  RtReportExchange reports_;
  int wake_fd_ = -1;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> started_{false};
  std::atomic<bool> safe_stop_{false};     // I/O -> RT: ramp to safe, refuse arming
  std::atomic<bool> safe_reached_{false};  // RT -> I/O: the ramp applied safe_u_V (stop_* below are written)
  std::int64_t safe_stop_begin_ns_ = 0;    // I/O thread: when begin_safe_stop() was first called
  SafeStopResult stop_result_;             // I/O thread, after the join or safe_reached()
  SetupStatus priority_status_;
  SetupStatus affinity_status_;

  // RT-thread state.
  double stop_u_start_V_ = 0.0;
  std::int64_t stop_ramp_ticks_ = 0;
  std::int64_t stop_reached_ns_ = 0;
  std::uint64_t ticks_skipped_ = 0;
  // Skipped ticks within the current second of the clock (bridge.max_stall_s).
  void note_skipped(std::int64_t k, std::uint64_t skipped) noexcept;
  std::int64_t max_stall_ticks_ = 0;
  std::int64_t stall_window_start_ = 0;
  std::uint64_t skipped_in_window_ = 0;
  std::uint64_t stall_trips_ = 0;
  std::int64_t last_stall_tick_ = -1;
  std::uint64_t last_stall_ticks_ = 0;
  // The soft position limits (ActuatorLimits::position_*): ticks in a row beyond, per axis.
  void check_positions(std::int64_t k, std::span<const StageReading> readings) noexcept;
  std::array<double, kMaxAxes> position_min_m_{};
  std::array<double, kMaxAxes> position_max_m_{};
  std::array<int, kMaxAxes> beyond_ticks_{};
  std::uint64_t position_trips_ = 0;
  int position_axis_ = -1;
  double position_m_ = 0.0;
  std::int64_t position_tick_ = -1;
  // The servo's oscillation detector per axis (BridgeSettings::oscillation), watching armed ticks.
  void check_oscillation(std::int64_t k, std::span<const BridgeTick> decided) noexcept;
  std::array<OscillationDetector, kMaxAxes> oscillation_{};
  std::uint64_t oscillation_trips_ = 0;
  int oscillation_axis_ = -1;
  double oscillation_hz_ = 0.0;
  double oscillation_rms_V_ = 0.0;
  std::int64_t oscillation_tick_ = -1;
  std::uint64_t ticks_caught_up_ = 0;
  std::uint64_t samples_dropped_ = 0;
  std::uint64_t commands_processed_ = 0;
  std::int64_t last_tick_ = -1;
  std::uint64_t trips_seen_ = 0;             // watchdog trips when last looked at
  std::int64_t last_trip_ns_ = -1;           // monotonic time of the tick that tripped last
  std::array<double, kMaxAxes> y_last_m_{};  // each axis's last measured position
  std::int64_t min_depth_period_ = -1;       // lowest buffer depth at an armed tick this report period
  std::int64_t min_depth_total_ = -1;        // ... since start (after the first command)
  bool commands_seen_ = false;
};

}  // namespace hystloop
