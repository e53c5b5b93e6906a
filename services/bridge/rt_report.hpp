#pragma once
// How the real-time thread hands its counters and timing histograms to the I/O thread
// once per status period without locking or copying the histograms: two report buffers,
// the RT thread fills one while the I/O thread reads the other.
//
//   I/O thread:  request();  ... later  if (const RtReport* r = take()) { use *r; release(); }
//   RT thread:   current() every tick;  serve_request([&](RtReport& r) { fill counters });
//
// The RT thread flips buffers only when asked, and the I/O thread asks again only after
// it released the buffer it took (it resets that buffer's windows), so the two never
// touch the same buffer.

#include <array>
#include <atomic>
#include <cstdint>

#include "core/latency_stats.hpp"
#include "loop/bridge_core.hpp"
#include "models/axis_coupling.hpp"

namespace hystloop {

struct RtReport {
  // Cumulative since start (the I/O thread subtracts a baseline for RESET_COUNTERS).
  BridgeCounters core{};
  std::uint64_t ticks_skipped = 0;       // timer deadlines passed over (overruns; hardware)
  std::uint64_t stall_trips = 0;         // ... beyond bridge.max_stall_s in a second: the safe state
  std::int64_t last_stall_tick = -1;     // the tick the last of those took effect at
  std::uint64_t last_stall_ticks = 0;    // ticks skipped within the second that tripped it
  std::uint64_t position_trips = 0;      // a measured position beyond its soft limit: the safe state
  int position_axis = -1;                // the last of those: its axis,
  double position_m = 0.0;               // the position that tripped it,
  std::int64_t position_tick = -1;       // and the tick
  std::uint64_t oscillation_trips = 0;   // a servo that oscillated (bridge.oscillation_*): the safe state
  int oscillation_axis = -1;             // the last of those: its axis,
  double oscillation_hz = 0.0;           // its frequency,
  double oscillation_rms_V = 0.0;        // the servo output's RMS above the corner,
  std::int64_t oscillation_tick = -1;    // and the tick
  std::uint64_t ticks_caught_up = 0;     // ticks run late, back to back, after an overrun (a simulator)
  std::uint64_t samples_dropped = 0;     // outgoing queue full: the I/O thread fell behind
  std::uint64_t commands_processed = 0;  // commands taken from the incoming queue
  std::int64_t last_tick = -1;
  std::int64_t last_trip_tick = -1;    // tick of the last watchdog trip
  std::int64_t last_trip_ns = -1;      // ... its monotonic time (a simulator's ticks may lag the wall clock)
  std::int64_t min_depth_period = -1;  // lowest buffer depth at an armed tick this period (-1: none)
  std::int64_t min_depth_total = -1;   // ... since the first command arrived
  std::int64_t buffer_depth = 0;       // now
  ClampCounts clamped_last_second{};   // armed ticks clamped in the last whole second of loop time
  double u_applied_V = 0.0;            // x's
  double gain_scale = 1.0;
  bool armed = false;
  // A stage of several axes: `core` above is the stage's (MultiAxisBridge::counters), these each axis's.
  int axes = 1;
  int tripped_by = -1;  // the axis whose watchdog last took the stage to the safe state (-1: none)
  std::array<BridgeCounters, kMaxAxes> axis_core{};
  std::array<double, kMaxAxes> axis_u_V{};
  // This report period's windows.
  LatencyStats work;      // RT work per tick (wake-up or the tick before's end, to sample pushed) [ns]
  LatencyStats lateness;  // timer wake-up lateness [ns]
};

class RtReportExchange {
 public:
  // I/O thread.
  void request() noexcept {
    if (!ready_.load(std::memory_order_acquire)) requested_.store(true, std::memory_order_release);
  }
  const RtReport* take() const noexcept {
    if (!ready_.load(std::memory_order_acquire)) return nullptr;
    return &buffers_[active_.load(std::memory_order_relaxed) ^ 1];
  }
  void release() noexcept {
    RtReport& r = buffers_[active_.load(std::memory_order_relaxed) ^ 1];
    r.work.reset();
    r.lateness.reset();
    ready_.store(false, std::memory_order_release);
  }

  // RT thread.
  RtReport& current() noexcept { return buffers_[active_.load(std::memory_order_relaxed)]; }
  template <class Fill>
  void serve_request(Fill&& fill) noexcept {
    if (!requested_.load(std::memory_order_acquire)) return;
    const unsigned a = active_.load(std::memory_order_relaxed);
    fill(buffers_[a]);
    active_.store(a ^ 1, std::memory_order_relaxed);
    requested_.store(false, std::memory_order_relaxed);
    ready_.store(true, std::memory_order_release);
  }

 private:
  RtReport buffers_[2];
  std::atomic<unsigned> active_{0};
  std::atomic<bool> requested_{false};
  std::atomic<bool> ready_{false};
};

}  // namespace hystloop
