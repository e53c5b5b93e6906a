#pragma once
// The re-identifier's settings from a config: the fields and their keys are
// common/reident/options.hpp (ReidentOptions).

#include "core/config.hpp"
#include "reident/options.hpp"

namespace hystloop {

// Reads and checks mem.{c1,c2,c3}, stage.* and reidentifier.*. Unknown reidentifier.* keys (and the old section
// reident:) are refused ("did you mean"); other sections belong to the processes sharing the file (the compensator
// checks the rest of mem.*). Throws ConfigError naming the field.
ReidentOptions read_reident_options(const Config& config);

}  // namespace hystloop
