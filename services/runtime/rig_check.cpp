#include "runtime/rig_check.hpp"

#include <cstdint>
#include <utility>

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include "core/errors.hpp"
#include "core/process.hpp"

namespace hystloop {
namespace {

std::optional<std::int64_t> counter(const service_status_t& msg, const std::string& name) {
  for (std::size_t i = 0; i < msg.counter_names.size() && i < msg.counter_values.size(); ++i) {
    if (msg.counter_names[i] == name) return msg.counter_values[i];
  }
  return std::nullopt;
}

const char* axis_text(int axis) { return axis == 0 ? "x" : axis == 1 ? "y" : "z"; }

}  // namespace

RigLimitsOwn RigLimitsOwn::from(const Config& config, int axis, const ActuatorFigures& limits, bool has_slew) {
  RigLimitsOwn o{axis, limits, has_slew, {}};
  for (std::size_t i = 0; i < kActuatorCounters.size(); ++i) {
    o.sources[i] = config.source_of("actuator." + std::string(kActuatorCounters[i].key));
  }
  return o;
}

std::optional<RigDifference> rig_limits_differ(const std::vector<RigLimitsOwn>& own, const std::string& process,
                                               const service_status_t& bridge) {
  for (const RigLimitsOwn& o : own) {
    for (std::size_t i = 0; i < kActuatorCounters.size(); ++i) {
      const ActuatorCounter& c = kActuatorCounters[i];
      if (!o.has_slew && c.value == &ActuatorFigures::slew_V_per_s) continue;
      const std::optional<std::int64_t> theirs = counter(bridge, actuator_counter_name(c, o.axis));
      if (!theirs) continue;  // a bridge that does not report them, or not this axis
      const auto mine = static_cast<std::int64_t>(actuator_counter(c, o.limits));
      if (mine == *theirs) continue;
      return RigDifference{
          "actuator." + std::string(c.key),
          fmt::format("{:g} in this {}'s configuration ({}), {:g} at the bridge on {} (pid {}, axis {}): a rig has one "
                      "set of actuator limits, the bridge's; give this process the bridge's",
                      o.limits.*c.value, process, o.sources[i], actuator_value(c, *theirs), bridge.host, bridge.pid,
                      axis_text(o.axis))};
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
