#pragma once
// The bridge's HX_STATUS state and detail from one report period's figures (BridgeService::report
// gathers them): STOPPING while the stop ramps, SAFE while disarmed (with the reason), otherwise
// DEGRADED for every reason that holds — commands late beyond bridge.degraded_late_fraction,
// samples dropped, repaired for the record or not published, commands refused for ticks too far
// ahead of the bridge's clock, ticks clamped by the range or the slew limit in the last
// whole second — each said in the detail, HEALTHY when none does. Plain data in and out, so it is tested alone.

#include <cstdint>
#include <string>

#include "loop/bridge_core.hpp"
#include "loop/oscillation_detector.hpp"

namespace hystloop {

struct BridgeHealthInput {
  bool stopping = false;
  bool armed = false;
  bool at_safe_voltage = false;  // disarmed and at actuator.safe_u_V (while stopping)
  double safe_u_V = 0.0;
  std::string safe_reason;                   // why the bridge is in the safe state
  double late_fraction = 0.0;                // late / armed ticks of the report period
  double degraded_late_fraction = 0.01;      // bridge.degraded_late_fraction
  std::uint64_t samples_dropped = 0;         // this report period
  std::uint64_t samples_repaired = 0;        // this period: ticks published with values the contract refused replaced
  std::uint64_t samples_unpublished = 0;     // this period: ticks the Publisher refused even so (not in the record)
  std::uint64_t commands_too_far_ahead = 0;  // this period: refused beyond bridge.max_lead_s (rejected_future)
  double max_lead_s = 0.0;                   // bridge.max_lead_s
  ClampCounts clamped_last_second{};
  std::uint64_t ticks_skipped = 0;  // this period: deadlines the hardware clock passed (outputs held stale)
  double dt_s = 1e-4;               // the tick
};

struct BridgeHealth {
  std::int8_t state = 0;  // service_status_t::HEALTHY, DEGRADED, SAFE or STOPPING
  std::string detail;     // empty when HEALTHY
};

BridgeHealth assess_bridge_health(const BridgeHealthInput& in);

// What the bridge can tell about why its command buffer ran dry, when the watchdog tripped: the
// compensator went quiet (no command block for long before the trip), its blocks were refused
// (forged, replayed, malformed: counted per reason on HX_STATUS), the real-time queue was full,
// or the bridge's own I/O thread was held up. Figures of the report period that saw the trip.
struct DryBufferFigures {
  double watchdog_s = 0.0;
  std::int64_t trip_tick = -1;
  int axes = 1;
  int tripped_by = -1;                   // the axis that ran dry first (-1: unknown)
  double since_last_command_s = -1.0;    // the last command block received -> the trip (< 0: none yet)
  bool command_after_trip = false;       // command blocks kept arriving after the trip (too late for their ticks)
  double period_s = 0.0;                 // the report period these counts are of
  std::uint64_t commands_rejected = 0;   // HX_COMMAND messages refused in the period (every reason)
  std::uint64_t command_queue_full = 0;  // command ticks the real-time queue had no room for
  double io_longest_pass_s = 0.0;        // the I/O thread's longest pass (dispatch, publish) in the period
  double io_longest_wait_s = 0.0;        // its longest time between two passes
};

// "watchdog: no command buffered for more than 0.002 s, tripped at tick 1234 (the last command
// block arrived 57.3 ms before; 120 HX_COMMAND messages refused in the last 1 s (120/s); the I/O
// thread's longest pass 0.4 ms, longest wait 20.1 ms); re-arm via HX_CONTROL"
std::string watchdog_reason(const DryBufferFigures& f);

// "the bridge's own clock stalled: 250 ticks (25 ms) skipped within one second, beyond
// bridge.max_stall_s 0.01 s: the outputs held stale voltages; every axis to the safe state at tick
// 81234 (real time on this host: docs/TIMING.md); re-arm via HX_CONTROL"
// "axis x's measured position 1.23 um beyond actuator.position_max_m 1 um for 3 ticks: every axis to
// the safe state at tick 4567; re-arm via HX_CONTROL"
std::string position_reason(int axis, double y_m, const ActuatorLimits& limits, int axes, std::int64_t tick);

// "axis x's servo oscillates at 5000 Hz: its output 7.1 V RMS above 300 Hz for 20 ms, beyond
// bridge.oscillation_rms_V 1 V: every axis to the safe state at tick 4567 (its gains or notch do not
// suit the stage: hystloop-ctl gains --stage-config checks them); re-arm via HX_CONTROL"
std::string oscillation_reason(int axis, double hz, double rms_V, const OscillationLimit& limit, int axes,
                               std::int64_t tick);

std::string stall_reason(std::uint64_t skipped_ticks, double max_stall_s, double rate_hz, std::int64_t tick);

}  // namespace hystloop
