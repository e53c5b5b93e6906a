#pragma once
// hystloop-identify's work: reads the inputs, fits the model args.choice names, prints the fit,
// writes the YAML snippet (--out) and publishes a MEM set (--publish). Returns the exit code:
// 0 fitted (and published); 1 no fit (the data cannot support one: the reason is printed,
// nothing published) or fitted but not published; 2 a file that cannot be used (not found,
// malformed, values beyond the sanity bounds, too many samples) or an LCM setup error.
#include "identify_args.hpp"

namespace hystloop {

int run_identify(const IdentifyArgs& args);

}  // namespace hystloop
