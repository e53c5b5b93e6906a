#pragma once
// The compensator's verdict on a trajectory, read from its HX_STATUS reports. No I/O here: the
// caller feeds the reports in. The compensator reports the last version it accepted
// (`trajectory_version`, shaped or not), the last it refused (`trajectory_refused_version`) and the
// last it shaped (`trajectory_shaped_version`), says why in its detail ("trajectory V refused: ..."
// or "trajectory V shaped: ...", and may note what it did with an accepted one: "trajectory V
// taken: ...") and reports right after it decides.

#include <cstdint>
#include <string>

#include "hystloop/service_status_t.hpp"

namespace hystloop::ctl {

enum class TrajectoryOutcome : std::int8_t {
  kPending,     // nothing about this version yet
  kAccepted,    // in use as sent
  kShaped,      // in use, shaped to the actuator's limits (detail: how)
  kRefused,     // not used (detail: why)
  kSuperseded,  // a later version was decided before this one was reported
};

struct TrajectoryVerdict {
  TrajectoryOutcome outcome = TrajectoryOutcome::kPending;
  std::string detail;              // the compensator's reason, for kShaped and kRefused
  std::int64_t later_version = 0;  // kSuperseded: the version decided instead
  bool has_counters = false;       // the report carries trajectory_version (a compensator that reports verdicts)
};

// What one report of the compensator says about `version`.
TrajectoryVerdict trajectory_verdict(const service_status_t& status, std::int64_t version);

// "trajectory <version> <what>: ", what the compensator's detail starts its verdict with.
std::string verdict_prefix(std::int64_t version, const std::string& what);

// The text after "trajectory <version> <what>: " in the detail (up to the end), else the whole
// detail ("" stays "").
std::string verdict_reason(const std::string& detail, std::int64_t version, const std::string& what);

}  // namespace hystloop::ctl
