#pragma once
// The `stage:` section, as the compensator (which inverts the stage) and the re-identifier (which
// takes it out of the data it fits) both read it: kind none | second_order, Banning's k [1/s^2]
// and c [1/s], and the order of the series. Bad input is a ConfigError naming the key.

#include "core/config.hpp"
#include "models/stage_inverse.hpp"

namespace hystloop {

// `defaults` supplies k and c when the section leaves them out; dt_s is the tick the stage must
// be invertible at (StageModel::validate).
StageModel read_stage_model(const Config& config, const StageModel& defaults, double dt_s);

}  // namespace hystloop
