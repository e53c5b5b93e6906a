#include "ctl_pin_model.hpp"

#include <string_view>
#include <vector>

#include "core/errors.hpp"
#include "lcm/feedforward_mode.hpp"

namespace hystloop::ctl {

std::int8_t pin_model_mode(const std::string& name) {
  if (name == "auto" || name == "off") return to_wire(FeedforwardMode::kOff);
  if (const auto kind = parse_model_kind(name)) return to_wire(mode_of(*kind));
  throw ParameterError("model", "expected " + pin_model_choices() + " (got \"" + name + "\")");
}

std::string pin_model_choices() {
  std::vector<std::string_view> names = model_kind_names();
  names.emplace_back("auto");
  return choice_list(names);
}

std::string reidentifier_process(int axis) {
  if (axis <= 0 || axis >= 3) return kPinModelTarget;
  return std::string(kPinModelTarget) + "-" + std::string(1, "xyz"[axis]);
}

}  // namespace hystloop::ctl
