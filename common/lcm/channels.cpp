#include "lcm/channels.hpp"

#include "core/errors.hpp"

namespace hystloop {

void validate_rig_prefix(std::string_view prefix) {
  const auto refuse = [&](const std::string& why) {
    throw ParameterError("rig.prefix", why + " (got \"" + std::string(prefix) + "\")");
  };
  if (prefix.empty() || prefix.size() > 32) refuse("must be 1..32 characters");
  if (prefix.front() < 'A' || prefix.front() > 'Z') refuse("must start with an upper-case letter");
  if (prefix.back() != '_') refuse("must end with '_'");
  for (char c : prefix) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    if (!ok) refuse("may contain only A-Z, 0-9 and '_' (LCM subscribes by regular expression)");
  }
}

std::string channel_name(std::string_view rig_prefix, std::string_view suffix) {
  validate_rig_prefix(rig_prefix);
  return std::string(rig_prefix).append(suffix);
}

ChannelNames::ChannelNames(std::string_view rig_prefix)
    : prefix((validate_rig_prefix(rig_prefix), std::string(rig_prefix))),
      sensor(prefix + std::string(kSensorSuffix)),
      command(prefix + std::string(kCommandSuffix)),
      trajectory(prefix + std::string(kTrajectorySuffix)),
      params(prefix + std::string(kParamsSuffix)),
      status(prefix + std::string(kStatusSuffix)),
      control(prefix + std::string(kControlSuffix)),
      model(prefix + std::string(kModelSuffix)),
      sim_truth(prefix + std::string(kSimTruthSuffix)),
      scan(prefix + std::string(kScanSuffix)) {}

}  // namespace hystloop
