#include "models/model_set.hpp"

#include <string>

#include "core/errors.hpp"

namespace hystloop {

std::string_view to_string(ModelKind kind) noexcept {
  std::string_view name = "unknown";
  OnlineModels::visit(kind, [&]<class D>() { name = D::name; });
  return name;
}

std::string describe_model(const ModelParamSet& set) {
  std::string summary = "?";
  OnlineModels::visit(set.kind, [&]<class D>() { summary = D::summary_of(set.*D::in_set); });
  return std::string(to_string(set.kind)) + ": " + summary;
}

std::vector<std::string_view> model_kind_names() {
  std::vector<std::string_view> names;
  names.reserve(kModelKindCount);
  for (int i = 0; i < kModelKindCount; ++i) names.push_back(to_string(static_cast<ModelKind>(i)));
  return names;
}

std::optional<ModelKind> parse_model_kind(std::string_view name) noexcept {
  for (int i = 0; i < kModelKindCount; ++i) {
    const auto kind = static_cast<ModelKind>(i);
    if (name == to_string(kind)) return kind;
  }
  return std::nullopt;
}

std::optional<ModelKind> model_kind_from_int(std::int64_t value) noexcept {
  if (value < 0 || value >= kModelKindCount) return std::nullopt;
  return static_cast<ModelKind>(value);
}

namespace {
template <class Params>
void validate_prefixed(const Params& params, std::string_view prefix) {
  validate_within(std::string(prefix) + ".", [&] { params.validate(); });
}
}  // namespace

void ModelParamSet::validate(double dt_s) const {
  if (stage) stage->validate(dt_s);
  if (!OnlineModels::visit(kind, [&]<class D>() { validate_prefixed(this->*D::in_set, D::name); })) {
    throw ParameterError("kind", "names no model");
  }
}

}  // namespace hystloop
