#include "runtime/rig_check.hpp"

#include <cmath>
#include <cstdint>
#include <utility>

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include "core/errors.hpp"
#include "core/process.hpp"
#include "lcm/status_counters.hpp"
#include "models/axis_coupling.hpp"

namespace hystloop {

RigLimitsOwn RigLimitsOwn::from(const Config& config, int axis, const ActuatorFigures& limits, bool has_slew) {
  RigLimitsOwn o;
  o.axis = axis;
  o.limits = limits;
  o.has_slew = has_slew;
  for (std::size_t i = 0; i < kActuatorCounters.size(); ++i) {
    o.sources[i] = config.source_of("actuator." + std::string(kActuatorCounters[i].key));
  }
  return o;
}

RigLimitsOwn RigLimitsOwn::with_gain(const Config& config, double gain_m_per_V, double factor,
                                     std::string factor_key) const {
  RigLimitsOwn o = *this;
  o.nominal_gain_m_per_V = gain_m_per_V;
  o.gain_factor = factor;
  o.gain_source = config.source_of("linear.gain");
  o.gain_factor_key = std::move(factor_key);
  return o;
}

std::optional<RigDifference> rig_limits_differ(const std::vector<RigLimitsOwn>& own, const std::string& process,
                                               const service_status_t& bridge) {
  for (const RigLimitsOwn& o : own) {
    if (const auto theirs = find_counter(bridge, axis_counter_name(kNominalGainCounter, o.axis));
        theirs && *theirs > 0 && std::isfinite(o.nominal_gain_m_per_V)) {
      const double bridge_gain = static_cast<double>(*theirs) / kNominalGainScale;
      const double ratio = o.nominal_gain_m_per_V / bridge_gain;
      if (ratio > o.gain_factor || ratio < 1.0 / o.gain_factor) {
        return RigDifference{
            "linear.gain",
            fmt::format("{:.4g} m/V in this {}'s configuration ({}), {:.4g} m/V at the bridge on {} (pid {}, axis {}: "
                        "servo.nominal_gain_m_per_V): more than x{:g} ({}) apart, so one of them is not this stage's "
                        "gain; set both from --probe-hardware --yes or an identification",
                        o.nominal_gain_m_per_V, process, o.gain_source, bridge_gain, bridge.host, bridge.pid,
                        axis_name(o.axis), o.gain_factor, o.gain_factor_key)};
      }
    }
    for (std::size_t i = 0; i < kActuatorCounters.size(); ++i) {
      const ActuatorCounter& c = kActuatorCounters[i];
      if (!o.has_slew && c.value == &ActuatorFigures::slew_V_per_s) continue;
      const std::optional<std::int64_t> theirs = find_counter(bridge, actuator_counter_name(c, o.axis));
      if (!theirs) continue;  // a bridge that does not report them, or not this axis
      const auto mine = static_cast<std::int64_t>(actuator_counter(c, o.limits));
      if (mine == *theirs) continue;
      return RigDifference{
          "actuator." + std::string(c.key),
          fmt::format("{:g} in this {}'s configuration ({}), {:g} at the bridge on {} (pid {}, axis {}): a rig has one "
                      "set of actuator limits, the bridge's; give this process the bridge's",
                      o.limits.*c.value, process, o.sources[i], actuator_value(c, *theirs), bridge.host, bridge.pid,
                      axis_name(o.axis))};
    }
  }
  return std::nullopt;
}

RigCheck::RigCheck(lcm::LCM& lcm, const std::string& status_channel, std::vector<RigLimitsOwn> own, std::string process)
    : own_(std::move(own)),
      process_(std::move(process)),
      status_(lcm, status_channel, [this](const service_status_t& msg, std::int64_t) { on_status(msg); }) {}

void RigCheck::on_status(const service_status_t& msg) {
  if (refusal_ || msg.process != "bridge") return;
  refusal_ = rig_limits_differ(own_, process_, msg);
  if (!refusal_) return;
  spdlog::error("refused: {}", refusal_->text());
  request_stop();
}

void RigCheck::throw_if_refused() const {
  if (refusal_) throw ParameterError(refusal_->key, refusal_->reason);
}

}  // namespace hystloop
