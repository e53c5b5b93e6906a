#pragma once
// scan_t (the wire) -> ScanSettings (what every axis's control law takes). The message has passed
// the contract check (common/lcm/message_checks.hpp); what is left is what depends on this
// stage: that the path's axes are among its `axes`, and the path's own validation
// (RasterSpec/LissajousSpec::validate), each refusal naming the field ("scan.fast_axis", ...).

#include "compensator/compensator_settings.hpp"
#include "hystloop/scan_t.hpp"

namespace hystloop {

// The path, blend and decouple flag of `msg` for a stage of `axes` axes (start_after_s unused:
// the caller maps msg.start_utime to loop time), a raster checked with the corners it will run with
// on `stage` (raster_corner_s). Throws ParameterError.
ScanSettings scan_from_message(const scan_t& msg, int axes, const StageModel& stage);

}  // namespace hystloop
