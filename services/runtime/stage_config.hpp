#pragma once
// The `stage:` section, as the compensator (which inverts the stage) and the re-identifier (which
// takes it out of the data it fits) both read it: kind none | second_order | linear, Banning's
// k [1/s^2] and c [1/s], and the order of the series; a linear stage in one of the forms a lab's
// identification prints (read_linear_stage). Bad input is a ConfigError naming the key.

#include <string>
#include <string_view>
#include <vector>

#include "core/config.hpp"
#include "models/linear_stage.hpp"
#include "models/stage_inverse.hpp"

namespace hystloop {

// `defaults` supplies k and c when the section leaves them out; dt_s is the tick the stage must
// be invertible at (StageModel::validate).
StageModel read_stage_model(const Config& config, const StageModel& defaults, double dt_s);

// A linear stage under `prefix` ("stage", "plant.stage") in one of the forms a lab prints
// (models/linear_stage.hpp): <prefix>.modes as [{frequency_hz, damping_ratio, weight}, ...] (weight:
// share of DC gain, default 1), <prefix>.zeros_hz / poles_hz as [[re, im], ...] in Hz (conjugate
// pairs listed once), <prefix>.numerator_s / denominator_s (highest power of s first), or
// <prefix>.numerator_zinv / denominator_zinv with discrete_dt_s; plus <prefix>.delay_s (fractional
// ticks allowed). An empty list is a form not given; two forms, or half of a pair, are refused
// naming the key; none: `stage` as given. Unit DC gain. Validated by the caller.
LinearStageSpec read_linear_stage(const Config& config, std::string_view prefix, LinearStageSpec stage);
// The keys read_linear_stage reads under `prefix`.
std::vector<std::string> linear_stage_keys(std::string_view prefix);
// One line for status and start-up: "second order k ... (1.72 kHz, zeta 0.094), inverted" or a
// linear stage's order, lowest resonance, delay and the preview its inverse takes.
std::string describe_stage(const StageModel& stage, double dt_s);
// Every key of the `stage:` section.
std::vector<std::string> stage_config_keys();

}  // namespace hystloop
