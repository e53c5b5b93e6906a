#pragma once
// `hystloop-ctl pin-model MODEL|auto` (MODEL: an online model, models/model_set.hpp): the re-identifier's online model
// choice (reidentifier.models) stops changing the model. A SET_MODE request addressed to the re-identifier
// ("reidentifier"; the compensator ignores requests for other processes): the mode names the model to
// pin (MODE_MEM, MODE_PI, ...); MODE_OFF ("auto", alias "off") lets it choose again. Pinned to a
// model not in use, the re-identifier fits it at its next selection and switches to it once.

#include <cstdint>
#include <string>

namespace hystloop::ctl {

inline constexpr const char* kPinModelTarget = "reidentifier";

// The re-identifier of `axis` (one process per axis): "reidentifier" for x, "reidentifier-y", "-z".
std::string reidentifier_process(int axis);

// The control_t mode for a pin-model argument; throws ParameterError("model") for anything else.
std::int8_t pin_model_mode(const std::string& name);
// "mem, pi, katalenic, linear or auto": what pin-model accepts (besides the alias "off").
std::string pin_model_choices();

}  // namespace hystloop::ctl
