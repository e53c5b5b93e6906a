#pragma once
// The re-identifier's settings from a config: the fields and their keys are
// common/reident/options.hpp (ReidentOptions).

#include "core/config.hpp"
#include "reident/options.hpp"

namespace hystloop {

// Reads and checks mem.* (the MEM's parameter table: the compensator's keys), stage.* and reidentifier.*. Unknown
// reidentifier.* and mem.* keys (and the old section reident:) are refused ("did you mean"); other sections belong
// to the processes sharing the file. Throws ConfigError naming the field.
ReidentOptions read_reident_options(const Config& config);

}  // namespace hystloop
