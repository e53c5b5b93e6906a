#include "models/hysteresis_plant.hpp"

#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>

#include "core/errors.hpp"

namespace hystloop {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// std::visit without its bad_variant_access path (a variant is valueless only after a throwing
// emplace, which the plant never does): a chain of get_if, so step/reset are noexcept for real.
template <std::size_t I = 0, class V, class F>
double visit_model(V& model, F&& f) noexcept {
  if constexpr (I < std::variant_size_v<V>) {
    if (auto* m = std::get_if<I>(&model)) return f(*m);
    return visit_model<I + 1>(model, f);
  } else {
    return kNaN;
  }
}

}  // namespace

std::string_view to_string(HysteresisPlantKind kind) noexcept {
  const auto i = static_cast<std::size_t>(kind);
  return i < kHysteresisPlantKindNames.size() ? kHysteresisPlantKindNames[i] : std::string_view("unknown");
}

std::optional<HysteresisPlantKind> parse_hysteresis_plant_kind(std::string_view name) noexcept {
  for (std::size_t i = 0; i < kHysteresisPlantKindNames.size(); ++i) {
    if (name == kHysteresisPlantKindNames[i]) return static_cast<HysteresisPlantKind>(i);
  }
  return std::nullopt;
}

HysteresisPlantKind hysteresis_plant_kind_from_name(std::string_view name, std::string_view field) {
  if (const std::optional<HysteresisPlantKind> kind = parse_hysteresis_plant_kind(name)) return *kind;
  throw ParameterError(std::string(field), "unknown hysteresis plant '" + std::string(name) + "'; expected " +
                                               choice_list(kHysteresisPlantKindNames));
}

PiParams default_plant_pi_params() { return pi_params_from_mem(MemParams::paper_like(), 15, 250.0); }

HysteresisPlantSpec HysteresisPlantSpec::named(std::string_view name) {
  HysteresisPlantSpec spec;
  spec.kind = hysteresis_plant_kind_from_name(name, "kind");
  return spec;
}

void HysteresisPlantSpec::validate() const {
  switch (kind) {
    case HysteresisPlantKind::coleman_hodgdon:
      validate_within("coleman_hodgdon.", [&] { coleman_hodgdon.validate(); });
      return;
    case HysteresisPlantKind::mem:
      validate_within("mem.", [&] { mem.validate(); });
      require_non_negative("mem_reversal_deadband_V", mem_reversal_deadband_V);
      return;
    case HysteresisPlantKind::pi: validate_within("pi.", [&] { pi.validate(); }); return;
    case HysteresisPlantKind::katalenic: validate_within("katalenic.", [&] { katalenic.validate(); }); return;
    case HysteresisPlantKind::bouc_wen: validate_within("bouc_wen.", [&] { bouc_wen.validate(); }); return;
    case HysteresisPlantKind::linear: validate_within("linear.", [&] { linear.validate(); }); return;
  }
  throw ParameterError("kind", "unknown hysteresis plant kind " + std::to_string(static_cast<int>(kind)) +
                                   "; expected " + choice_list(kHysteresisPlantKindNames));
}

HysteresisPlant::Model HysteresisPlant::make_model(const HysteresisPlantSpec& spec) {
  spec.validate();
  switch (spec.kind) {
    case HysteresisPlantKind::coleman_hodgdon: return Model(std::in_place_type<ColemanHodgdon>, spec.coleman_hodgdon);
    case HysteresisPlantKind::mem: return Model(std::in_place_type<MemModel>, spec.mem, spec.mem_reversal_deadband_V);
    case HysteresisPlantKind::pi: return Model(std::in_place_type<PiModel>, spec.pi);
    case HysteresisPlantKind::katalenic: return Model(std::in_place_type<KatalenicModel>, spec.katalenic);
    case HysteresisPlantKind::bouc_wen: return Model(std::in_place_type<BoucWen>, spec.bouc_wen);
    case HysteresisPlantKind::linear: return Model(std::in_place_type<LinearModel>, spec.linear);
  }
  throw ParameterError("kind", "unknown hysteresis plant kind");  // validate() has refused it already
}

HysteresisPlant::HysteresisPlant(const HysteresisPlantSpec& spec) : spec_(spec), model_(make_model(spec)) {
  reset(0.0);
}

void HysteresisPlant::reset(double u0_V) noexcept {
  const double u0 = std::isfinite(u0_V) ? u0_V : 0.0;
  u_ = u0;
  y_ = visit_model(model_, [u0](auto& m) noexcept -> double {
    using M = std::decay_t<decltype(m)>;
    m.reset(u0);
    if constexpr (std::is_same_v<M, LinearModel>) {
      return m.params().gain * u0 + m.params().offset;
    } else {
      return m.output();
    }
  });
}

double HysteresisPlant::step(double u_V, double dt_s) noexcept {
  if (!std::isfinite(u_V) || !std::isfinite(dt_s) || !(dt_s > 0.0)) return kNaN;
  y_ = visit_model(model_, [u_V](auto& m) noexcept { return m.forward(u_V); });
  u_ = u_V;
  return y_;
}

}  // namespace hystloop
