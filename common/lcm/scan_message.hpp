#pragma once
// scan_t (the wire) -> the path it describes (loop/scan_path.hpp), field by field and nothing
// more: what the compensator runs and what hystloop-report measures a log's paths against are
// read by this one function. The stage's own checks (its axes, the corners it runs with) are the
// caller's.

#include <variant>

#include "hystloop/scan_t.hpp"
#include "loop/scan_path.hpp"

namespace hystloop {

// The raster or Lissajous figure `msg` gives, with its centre. `msg` has passed check_message
// (axes 0..2: a negative axis would read as 128 or more, which every stage refuses). Throws ParameterError("scan.path")
// for a path kind it does not know.
std::variant<RasterSpec, LissajousSpec> scan_path_of(const scan_t& msg);

}  // namespace hystloop
