#pragma once
// A rig has one set of actuator limits, and the bridge's are the rig's: it applies them to every
// tick. A compensator plans inside its own copy and a re-identifier judges fitted models over its
// own; copies typed into three files on two hosts drift apart. RigCheck listens to HX_STATUS, and
// at every report of a bridge of this rig that carries its limits (lcm/actuator_status.hpp)
// compares them with this process's own: on the first difference it logs an error naming both
// values and where each came from, and asks the process to stop; the service then exits 2, as for
// any configuration it refuses. A bridge restarted with other limits is caught the same way.
// HX_STATUS is not signed: a forged report can stop a service this way, never make it run with
// limits other than its own.

#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "core/config.hpp"
#include "hystloop/service_status_t.hpp"
#include "lcm/actuator_status.hpp"
#include "lcm/subscription.hpp"

namespace hystloop {

struct RigLimitsOwn {
  int axis = 0;  // the bridge's axis these are for (0 = x)
  ActuatorFigures limits{};
  bool has_slew = true;  // false: only the range is this process's (the re-identifier)
  // Where each limit came from (a file, "--set"), in kActuatorCounters' order.
  std::array<std::string, kActuatorCounters.size()> sources{};
  // The stage's nominal gain this process judges models against (linear.gain) and the factor it
  // allows them off it: refused when the bridge's servo.nominal_gain_m_per_V is further off than
  // that (one of the two is not this stage's). NaN: not compared.
  double nominal_gain_m_per_V = std::numeric_limits<double>::quiet_NaN();
  double gain_factor = 10.0;
  std::string gain_source;
  std::string gain_factor_key;  // "compensator.plausible_gain_factor"

  // Axis `axis`'s limits as `config` gave them (actuator.u_min_V ...: one set for every axis).
  static RigLimitsOwn from(const Config& config, int axis, const ActuatorFigures& limits, bool has_slew);
  // ... and the nominal gain (linear.gain) with its factor, named by `factor_key`.
  RigLimitsOwn with_gain(const Config& config, double gain_m_per_V, double factor, std::string factor_key) const;
};

// One limit this process and the bridge disagree on: its key and why, naming both values.
struct RigDifference {
  std::string key;  // "actuator.u_max_V"
  std::string reason;
  std::string text() const { return key + ": " + reason; }
};

// The first of `own`'s limits that a bridge's report `bridge` gives otherwise (to its 1 mV);
// nullopt when they agree, or the report carries no limits for those axes. `process` names this
// process in the reason.
std::optional<RigDifference> rig_limits_differ(const std::vector<RigLimitsOwn>& own, const std::string& process,
                                               const service_status_t& bridge);

class RigCheck {
 public:
  // Subscribes to `status_channel` on `lcm`, which must outlive it.
  RigCheck(lcm::LCM& lcm, const std::string& status_channel, std::vector<RigLimitsOwn> own, std::string process);

  // Why this process was refused, once a bridge's report differed.
  const std::optional<RigDifference>& refusal() const noexcept { return refusal_; }
  // Throws ParameterError(key, reason) when there is one: what the service's run() calls
  // after its loop, so that the process exits 2.
  void throw_if_refused() const;

 private:
  void on_status(const service_status_t& msg);

  std::vector<RigLimitsOwn> own_;
  std::string process_;
  std::optional<RigDifference> refusal_;
  Subscription<service_status_t> status_;
};

}  // namespace hystloop
