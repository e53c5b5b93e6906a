#include "ctl_verdict.hpp"

#include <algorithm>

#include "ctl_health.hpp"

namespace hystloop::ctl {

std::string verdict_prefix(std::int64_t version, const std::string& what) {
  return "trajectory " + std::to_string(version) + " " + what + ": ";
}

std::string verdict_reason(const std::string& detail, std::int64_t version, const std::string& what) {
  const std::string prefix = verdict_prefix(version, what);
  const auto at = detail.find(prefix);
  return at == std::string::npos ? detail : detail.substr(at + prefix.size());
}

TrajectoryVerdict trajectory_verdict(const service_status_t& status, std::int64_t version) {
  TrajectoryVerdict v;
  const auto accepted = find_counter(status, "trajectory_version");
  const auto refused = find_counter(status, "trajectory_refused_version");
  const auto shaped = find_counter(status, "trajectory_shaped_version");
  v.has_counters = accepted.has_value();
  if (refused == version) {
    v.outcome = TrajectoryOutcome::kRefused;
    v.detail = verdict_reason(status.detail, version, "refused");
  } else if (accepted == version) {
    const bool was_shaped = shaped == version;
    v.outcome = was_shaped ? TrajectoryOutcome::kShaped : TrajectoryOutcome::kAccepted;
    if (was_shaped) {
      v.detail = verdict_reason(status.detail, version, "shaped");
    } else if (status.detail.find(verdict_prefix(version, "taken")) != std::string::npos) {
      v.detail = verdict_reason(status.detail, version, "taken");  // a note on what it did, if any
    }
  } else if (std::max(accepted.value_or(0), refused.value_or(0)) > version) {
    v.outcome = TrajectoryOutcome::kSuperseded;
    v.later_version = std::max(accepted.value_or(0), refused.value_or(0));
  }
  return v;
}

}  // namespace hystloop::ctl
