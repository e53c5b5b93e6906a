#pragma once
// YAML config snippets for identified parameters, written through each model's parameter table
// (models/model_descriptors.hpp): keys are the table's names (mem: {c1, c2, c3}, banning:
// {hysteresis: {a, b, alpha, s_max}, stage: {k, c}, order}, ...), values in SI, each the shortest
// text that reads back to the same double, so the snippet can be pasted into a hystloop config
// file or given to hystloop-model --params-file and reads back unchanged.

#include <string>

#include "models/banning_stage.hpp"
#include "models/katalenic.hpp"
#include "models/linear.hpp"
#include "models/mem.hpp"
#include "models/prandtl_ishlinskii.hpp"

namespace hystloop {

std::string to_yaml(const MemParams& p);
std::string to_yaml(const PiParams& p);
std::string to_yaml(const LinearParams& p);
std::string to_yaml(const KatalenicParams& p);
std::string to_yaml(const ColemanHodgdonParams& h, const SecondOrderStageParams* stage);  // banning:

}  // namespace hystloop
