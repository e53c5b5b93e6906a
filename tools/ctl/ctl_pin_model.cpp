#include "ctl_pin_model.hpp"

#include "core/errors.hpp"
#include "lcm/feedforward_mode.hpp"

namespace hystloop::ctl {

std::int8_t pin_model_mode(const std::string& name) {
  if (name == "auto" || name == "off") return to_wire(FeedforwardMode::kOff);
  if (const auto kind = parse_model_kind(name)) return to_wire(mode_of(*kind));
  std::string names;
  for (int i = 0; i < kModelKindCount; ++i) names.append(to_string(static_cast<ModelKind>(i))).append(", ");
  throw ParameterError("model", "expected " + names.substr(0, names.size() - 2) + " or auto (got \"" + name + "\")");
}

}  // namespace hystloop::ctl
