#pragma once
// One parameter set of any of the models the compensator can invert online: which model, and its
// parameters. It is what the re-identifier publishes (lcmtypes/model_params_t.lcm carries it on
// the wire) and what the compensator swaps in at a reversal. Banning's model needs its own
// experiments and is identified offline only, so it is not a kind here.

#include <cstdint>
#include <optional>
#include <string_view>

#include "models/katalenic.hpp"
#include "models/linear.hpp"
#include "models/mem.hpp"
#include "models/prandtl_ishlinskii.hpp"
#include "models/stage_inverse.hpp"

namespace hystloop {

// Numbering shared with model_params_t.kind on the wire; never renumber.
enum class ModelKind : std::int8_t { mem = 0, pi = 1, katalenic = 2, linear = 3 };
inline constexpr int kModelKindCount = 4;

std::string_view to_string(ModelKind kind) noexcept;
// "mem|pi|katalenic|linear"; nullopt for anything else.
std::optional<ModelKind> parse_model_kind(std::string_view name) noexcept;
// The wire's number; nullopt when it names no model.
std::optional<ModelKind> model_kind_from_int(std::int64_t value) noexcept;

// One parameter struct of every online model: the one list of their members (a model added
// here, in ModelKind and in OnlineModels is known to the message, the compensator's config and
// inverses, validation and summaries).
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

}  // namespace hystloop
