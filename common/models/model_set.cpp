#include "models/model_set.hpp"

#include <string>

#include "core/errors.hpp"

namespace hystloop {

std::string_view to_string(ModelKind kind) noexcept {
  switch (kind) {
    case ModelKind::mem: return "mem";
    case ModelKind::pi: return "pi";
    case ModelKind::katalenic: return "katalenic";
    case ModelKind::linear: return "linear";
  }
  return "unknown";
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
void validate_prefixed(const Params& params, const char* prefix) {
  try {
    params.validate();
  } catch (const ParameterError& e) {
    const std::string what = e.what();  // "field: reason"
    throw ParameterError(std::string(prefix) + "." + e.field(), what.substr(e.field().size() + 2));
  }
}
}  // namespace

void ModelParamSet::validate(double dt_s) const {
  if (stage) stage->validate(dt_s);
  switch (kind) {
    case ModelKind::mem: return validate_prefixed(mem, "mem");
    case ModelKind::pi: return validate_prefixed(pi, "pi");
    case ModelKind::katalenic: return validate_prefixed(katalenic, "katalenic");
    case ModelKind::linear: return validate_prefixed(linear, "linear");
  }
  throw ParameterError("kind", "names no model");
}

}  // namespace hystloop
