#pragma once
// Which feedforward the compensator plans: off, one of the online models' inverses, or an
// identification experiment's raw voltage. The numbering is the wire's (command_block_t.mode,
// control_t.mode; lcm/feedforward_mode.hpp checks it), and a model's mode is the number its entry
// in OnlineModels (models/model_set.hpp) gives it: one added there takes the next free number and
// needs no enumerator here. It lives beside the models, not the loop, because the messages, the
// tools and the compensator all name modes, and only the compensator plans them.

#include <cstdint>
#include <optional>
#include <string>

#include "models/model_set.hpp"

namespace hystloop {

enum class FeedforwardMode : std::int8_t {
  kOff = 0,        // no feedforward: u_ff = 0 (the bridge's servo alone)
  kLinear = 1,     // static gain: the MEM paper's "linear feedforward"
  kMem = 2,        // hybrid MEM element inverse (Strijbosch et al., Theorem 10)
  kPi = 3,         // Prandtl-Ishlinskii inverse
  kKatalenic = 4,  // Lambert-W operator inverse
  kExperiment = 5  // identification excitation: raw voltage, no reference (not selectable as a mode)
};

// Parses "off|linear|mem|pi|katalenic"; throws ParameterError naming `field`.
FeedforwardMode parse_feedforward_mode(const std::string& name, const std::string& field = "compensator.mode");
// "off, linear, mem, pi or katalenic": the modes a config or SET_MODE may select, in wire order.
std::string selectable_mode_choices();
const char* to_string(FeedforwardMode mode) noexcept;
// The mode that inverts `kind`, and the model a mode inverts (none for off and experiment).
FeedforwardMode mode_of(ModelKind kind) noexcept;
std::optional<ModelKind> model_kind_of(FeedforwardMode mode) noexcept;

}  // namespace hystloop
