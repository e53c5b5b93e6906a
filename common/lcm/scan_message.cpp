#include "lcm/scan_message.hpp"

#include <string>

#include "core/errors.hpp"

namespace hystloop {

std::variant<RasterSpec, LissajousSpec> scan_path_of(const scan_t& msg) {
  AxisPositions centre{};
  for (std::size_t i = 0; i < kScanAxes; ++i) centre[i] = msg.centre_m[i];
  if (msg.path == scan_t::RASTER) {
    RasterSpec r;
    // 0..2 (check_message), so the unsigned byte is the axis.
    r.fast_axis = static_cast<unsigned char>(msg.fast_axis);
    r.slow_axis = static_cast<unsigned char>(msg.slow_axis);
    r.width_m = msg.width_m;
    r.height_m = msg.height_m;
    r.lines = msg.lines;
    r.line_rate_hz = msg.line_rate_Hz;
    r.slow_mode = msg.slow_mode == scan_t::RAMP ? SlowMode::kRamp : SlowMode::kSteps;
    r.corner_s = msg.corner_s;
    r.settle_s = msg.settle_s;
    r.centre_m = centre;
    return r;
  }
  if (msg.path == scan_t::LISSAJOUS) {
    LissajousSpec l;
    for (std::size_t i = 0; i < kScanAxes; ++i) {
      l.amplitude_m[i] = msg.amplitude_m[i];
      l.frequency_hz[i] = msg.frequency_Hz[i];
      l.phase_rad[i] = msg.phase_rad[i];
    }
    l.duration_s = msg.duration_s;
    l.centre_m = centre;
    return l;
  }
  throw ParameterError("scan.path", "must be RASTER (1) or LISSAJOUS (2), got " + std::to_string(msg.path));
}

}  // namespace hystloop
