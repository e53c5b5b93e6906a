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
};

struct BridgeHealth {
  std::int8_t state = 0;  // service_status_t::HEALTHY, DEGRADED, SAFE or STOPPING
  std::string detail;     // empty when HEALTHY
};

BridgeHealth assess_bridge_health(const BridgeHealthInput& in);

}  // namespace hystloop
