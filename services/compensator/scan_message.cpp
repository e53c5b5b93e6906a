#include "compensator/scan_message.hpp"

#include <string>

#include "core/errors.hpp"

namespace hystloop {

namespace {
// `axis` when the stage has it, else throws naming `field`.
int require_axis(const char* field, int axis, int axes) {
  if (axis < 0 || axis >= axes) {
    throw ParameterError(field, "names axis " + std::string(axis_name(axis)) + ", but this stage has " +
                                    std::to_string(axes) + (axes == 1 ? " axis" : " axes"));
  }
  return axis;
}
}  // namespace

ScanSettings scan_from_message(const scan_t& msg, int axes, const StageModel& stage) {
  ScanSettings s;
  s.blend_s = msg.blend_s;
  s.decouple = msg.decouple != 0;
  AxisPositions centre{};
  for (std::size_t i = 0; i < kScanAxes; ++i) centre[i] = msg.centre_m[i];
  if (msg.path == scan_t::RASTER) {
    s.path = ScanSettings::Path::kRaster;
    RasterSpec& r = s.raster;
    r.fast_axis = require_axis("scan.fast_axis", msg.fast_axis, axes);
    r.slow_axis = require_axis("scan.slow_axis", msg.slow_axis, axes);
    r.width_m = msg.width_m;
    r.height_m = msg.height_m;
    r.lines = msg.lines;
    r.line_rate_hz = msg.line_rate_Hz;
    r.slow_mode = msg.slow_mode == scan_t::RAMP ? SlowMode::kRamp : SlowMode::kSteps;
    r.corner_s = msg.corner_s;
    r.settle_s = msg.settle_s;
    r.centre_m = centre;
    RasterSpec checked = r;  // with the corners it will run with
    checked.corner_s = raster_corner_s(r, stage);
    checked.validate();
  } else if (msg.path == scan_t::LISSAJOUS) {
    s.path = ScanSettings::Path::kLissajous;
    LissajousSpec& l = s.lissajous;
    for (std::size_t i = 0; i < kScanAxes; ++i) {
      l.amplitude_m[i] = msg.amplitude_m[i];
      l.frequency_hz[i] = msg.frequency_Hz[i];
      l.phase_rad[i] = msg.phase_rad[i];
      if (static_cast<int>(i) >= axes && l.amplitude_m[i] != 0.0) {
        require_axis("scan.amplitude_m", static_cast<int>(i), axes);
      }
    }
    l.duration_s = msg.duration_s;
    l.centre_m = centre;
    l.validate();
  } else {
    throw ParameterError("scan.path", "must be RASTER (1) or LISSAJOUS (2), got " + std::to_string(msg.path));
  }
  return s;
}

}  // namespace hystloop
