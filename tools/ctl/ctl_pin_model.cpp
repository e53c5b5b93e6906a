#include "ctl_pin_model.hpp"

#include <string_view>
#include <vector>

#include "core/errors.hpp"
#include "lcm/feedforward_mode.hpp"

namespace hystloop::ctl {

std::int8_t pin_model_mode(const std::string& name) {
  if (name == "auto" || name == "off") return to_wire(FeedforwardMode::kOff);
  if (const auto kind = parse_model_kind(name)) return to_wire(mode_of(*kind));
  std::vector<std::string_view> names;
  names.reserve(kModelKindCount + 1);
  for (int i = 0; i < kModelKindCount; ++i) names.push_back(to_string(static_cast<ModelKind>(i)));
  names.emplace_back("auto");
  throw ParameterError("model", "expected " + choice_list(names) + " (got \"" + name + "\")");
}

std::string reidentifier_process(int axis) {
  if (axis <= 0 || axis >= 3) return kPinModelTarget;
  return std::string(kPinModelTarget) + "-" + std::string(1, "xyz"[axis]);
}

}  // namespace hystloop::ctl
