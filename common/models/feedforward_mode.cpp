#include "models/feedforward_mode.hpp"

#include <algorithm>
#include <string_view>
#include <utility>
#include <vector>

#include "core/errors.hpp"

namespace hystloop {

// Each online model's mode number is its registry entry's (models/model_set.hpp).
FeedforwardMode mode_of(ModelKind kind) noexcept {
  FeedforwardMode mode = FeedforwardMode::kOff;
  OnlineModels::visit(kind, [&]<class D>() { mode = static_cast<FeedforwardMode>(D::mode); });
  return mode;
}

std::optional<ModelKind> model_kind_of(FeedforwardMode mode) noexcept {
  std::optional<ModelKind> kind;
  OnlineModels::for_each([&]<class D>() {
    if (static_cast<FeedforwardMode>(D::mode) == mode) kind = D::kind;
  });
  return kind;
}

// The models' names are ModelKind's (models/model_set.cpp): one table for the compensator's
// config, HX_CONTROL's SET_MODE (hystloop-ctl mode) and the re-identifier's model choice.
FeedforwardMode parse_feedforward_mode(const std::string& name, const std::string& field) {
  if (name == "off") return FeedforwardMode::kOff;
  if (const auto kind = parse_model_kind(name)) return mode_of(*kind);
  throw ParameterError(field, "unknown mode '" + name + "' (expected " + selectable_mode_choices() + ")");
}

std::string selectable_mode_choices() {
  std::vector<std::pair<std::int8_t, std::string_view>> modes{{static_cast<std::int8_t>(FeedforwardMode::kOff), "off"}};
  OnlineModels::for_each([&]<class D>() { modes.emplace_back(D::mode, D::name); });
  std::sort(modes.begin(), modes.end());
  std::vector<std::string_view> names;
  names.reserve(modes.size());
  for (const auto& [number, name] : modes) names.push_back(name);
  return choice_list(names);
}

const char* to_string(FeedforwardMode mode) noexcept {
  if (mode == FeedforwardMode::kOff) return "off";
  if (mode == FeedforwardMode::kExperiment) return "experiment";
  if (const auto kind = model_kind_of(mode)) return to_string(*kind).data();  // a literal: NUL-terminated
  return "unknown";
}

}  // namespace hystloop
