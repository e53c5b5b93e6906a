#pragma once
// YAML config snippets for identified parameters. Keys are the parameter structs' member names
// (mem: {c1, c2, c3}, banning: {hysteresis: {a, b, alpha}, stage: {k, c}}, ...), values in SI
// with full precision, so the snippet can be pasted into a hystloop config file.

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
