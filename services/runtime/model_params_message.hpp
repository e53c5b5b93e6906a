#pragma once
// model_params_t (HX_MODEL) <-> ModelParamSet, and mem_params_t (HX_PARAMS) <-> MEM. The message
// carries every model's fields; only those of `kind` are written (the rest left at 0) and read.

#include <optional>

#include "hystloop/mem_params_t.hpp"
#include "hystloop/model_params_t.hpp"
#include "models/model_set.hpp"

namespace hystloop {

// Writes the kind and its parameters (format_version = FORMAT_VERSION); leaves utime, version,
// publisher_id and the fit's figures as they are. Fields of the other kinds are zeroed.
void set_model(model_params_t& msg, const ModelParamSet& set);

// The parameter set of a message check_model_params_envelope() accepted; nullopt when the kind
// or format version is not one this build knows. Not validated: call ModelParamSet::validate()
// (throws ParameterError naming the field, e.g. "pi.weights[3]").
std::optional<ModelParamSet> model_from_message(const model_params_t& msg);

// The MEM set of an HX_PARAMS message, as a ModelParamSet of kind mem.
ModelParamSet model_from_message(const mem_params_t& msg) noexcept;

}  // namespace hystloop
