#pragma once
// The re-identifier's settings from a config: the fields and their keys are
// common/reident/options.hpp (ReidentOptions).

#include "core/config.hpp"
#include "reident/options.hpp"
#include "runtime/rig_check.hpp"

namespace hystloop {

// Reads and checks mem.* (the MEM's parameter table: the compensator's keys), stage.* and reidentifier.*. Unknown
// reidentifier.* and mem.* keys (and the old section reident:) are refused ("did you mean"); other sections belong
// to the processes sharing the file. Throws ConfigError naming the field.
ReidentOptions read_reident_options(const Config& config);

// The actuator range `options` judges models over (its axis's), with where it came from: held
// against the bridge's at run time (runtime/rig_check.hpp).
RigLimitsOwn reident_rig_limits(const Config& config, const ReidentOptions& options);

}  // namespace hystloop
