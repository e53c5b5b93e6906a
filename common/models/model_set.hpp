#pragma once
// The online models' registry: every model the compensator can invert online and the
// re-identifier can fit, its number, its parameters' member and its feedforward mode, in one
// place. A parameter set of any of them (ModelParamSet) is what the re-identifier publishes
// (lcmtypes/model_params_t.lcm carries it on the wire) and what the compensator swaps in at a
// reversal. Code over every such model (the message, validation, plausibility, summaries, the
// compensator's config and inverses) iterates OnlineModels and names none of them, so a model is
// added in its own files (its model, its descriptor <model>_descriptor.hpp/.cpp) and here, and its
// fields on the wire in model_params_t.lcm. Banning's model needs its own experiments and is
// identified offline only, so it is not one of them.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "models/katalenic_descriptor.hpp"
#include "models/linear_descriptor.hpp"
#include "models/mem_descriptor.hpp"
#include "models/pi_descriptor.hpp"
#include "models/stage_inverse.hpp"

namespace hystloop {

// Numbering shared with model_params_t.kind on the wire; never renumber.
enum class ModelKind : std::int8_t { mem = 0, pi = 1, katalenic = 2, linear = 3 };
inline constexpr int kModelKindCount = 4;

// One parameter struct of every online model.
struct ModelParams {
  MemParams mem{};
  PiParams pi{};
  KatalenicParams katalenic{};
  LinearParams linear{};
};

struct ModelParamSet : ModelParams {
  ModelKind kind = ModelKind::mem;
  // Only the member that `kind` names is meaningful; the others keep their defaults.
  // The stage in series with the hysteresis, when the set says (nullopt: the receiver keeps the
  // stage it has; a hysteresis refit says nothing of the stage).
  std::optional<StageModel> stage;

  // Validates the member `kind` names (and the stage, at tick dt_s); throws ParameterError naming
  // the field ("pi.weights[3]", "stage.c").
  void validate(double dt_s = 1e-4) const;
};

// A model's descriptor as the registry places it: its kind, its member of ModelParams and the
// number of its feedforward mode (command_block_t.MODE_*, FeedforwardMode).
template <class Descriptor, ModelKind Kind, auto Member, std::int8_t Mode>
struct OnlineModel : Descriptor {
  static constexpr ModelKind kind = Kind;
  static constexpr auto in_set = Member;
  static constexpr std::int8_t mode = Mode;
};

// The models a ModelParamSet holds, one for each ModelKind: what code over every such model
// iterates. F is a generic lambda []<class D>() {...} called with each model's descriptor.
template <class... D>
struct ModelList {
  static_assert(sizeof...(D) == kModelKindCount, "one descriptor per ModelKind");

  template <class F>
  static void for_each(F&& f) {
    (f.template operator()<D>(), ...);
  }
  // f for the model `kind` names; false when it names none.
  template <class F>
  static bool visit(ModelKind kind, F&& f) {
    return ((kind == D::kind && (f.template operator()<D>(), true)) || ...);
  }
};
using OnlineModels = ModelList<OnlineModel<MemDescriptor, ModelKind::mem, &ModelParams::mem, 2>,
                               OnlineModel<PiDescriptor, ModelKind::pi, &ModelParams::pi, 3>,
                               OnlineModel<KatalenicDescriptor, ModelKind::katalenic, &ModelParams::katalenic, 4>,
                               OnlineModel<LinearDescriptor, ModelKind::linear, &ModelParams::linear, 1>>;

std::string_view to_string(ModelKind kind) noexcept;
// "mem|pi|katalenic|linear"; nullopt for anything else.
std::optional<ModelKind> parse_model_kind(std::string_view name) noexcept;
// The wire's number; nullopt when it names no model.
std::optional<ModelKind> model_kind_from_int(std::int64_t value) noexcept;

// "mem: c1 5.3e-09 m/V, c2 2.1e-12 m/V^(1+c3), c3 1.15": the set's model and its summary.
std::string describe_model(const ModelParamSet& set);

}  // namespace hystloop
