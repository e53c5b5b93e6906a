#pragma once
// The models hystloop-model can run, by name: each entry is a model's descriptor and parameter
// table (models/model_descriptors.hpp) and builds a runner for one file. The runner is virtual
// per file; the per-sample loop inside it is a template over the model type (model_concepts.hpp),
// so no sample pays a virtual call.

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "models/param_table.hpp"

namespace hystloop::model_tool {

// A configured model, run over a whole file. Inputs are finite; t is increasing when the entry
// says it needs it. The first sample sets the initial state: forward starts as the model's
// reset(u[0]) does (virgin/equilibrium state at u[0]), inverse as reset(y_ref[0]) does, the state
// the forward model reaches for the same point, so forward-then-inverse gives u back.
class ModelRun {
 public:
  virtual ~ModelRun() = default;
  // u [V] at times t [s] -> y [m].
  virtual std::vector<double> forward(const std::vector<double>& t, const std::vector<double>& u) const = 0;
  // y_ref [m] at times t [s] -> u [V]. Only when the entry has_inverse().
  virtual std::vector<double> inverse(const std::vector<double>& t, const std::vector<double>& y_ref) const = 0;
};

struct ModelEntry {
  std::string_view name;
  std::string_view summary;  // one line for --help
  std::string_view notes;    // extra help lines ("" if none)
  bool has_inverse = false;
  bool uses_time = false;  // dynamics: dt from the t column
  std::vector<ParamInfo> (*parameters)() = nullptr;
  // Defaults, then each assignment in order, then the model's validate(). Throws AssignmentError
  // for an unknown name or malformed value, ParameterError (naming the field) for an invalid set.
  std::unique_ptr<ModelRun> (*configure)(const std::vector<Assignment>& assignments) = nullptr;
};

// Every model, in the order --help lists them.
std::span<const ModelEntry* const> model_registry();
// nullptr if unknown.
const ModelEntry* find_model(std::string_view name);
// "mem, pi, katalenic, linear, banning"
std::string model_names(std::string_view separator = ", ");
// The models with an inverse (feedforward), in the same order: "mem, pi, katalenic, linear".
std::string invertible_model_names(std::string_view separator = ", ");

// The --help section: every model, its parameters with unit, default and meaning.
std::string models_help();

}  // namespace hystloop::model_tool
