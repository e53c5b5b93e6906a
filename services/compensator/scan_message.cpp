#include "compensator/scan_message.hpp"

#include <string>
#include <variant>

#include "core/errors.hpp"
#include "lcm/scan_message.hpp"

namespace hystloop {

namespace {
// Throws naming `field` unless the stage has `axis`.
void require_axis(const char* field, int axis, int axes) {
  if (axis < 0 || axis >= axes) {
    throw ParameterError(field, "names axis " + std::string(axis_name(axis)) + ", but this stage has " +
                                    std::to_string(axes) + (axes == 1 ? " axis" : " axes"));
  }
}
}  // namespace

ScanSettings scan_from_message(const scan_t& msg, int axes, const StageModel& stage) {
  ScanSettings s;
  s.blend_s = msg.blend_s;
  s.decouple = msg.decouple != 0;
  const std::variant<RasterSpec, LissajousSpec> path = scan_path_of(msg);
  if (const auto* raster = std::get_if<RasterSpec>(&path)) {
    s.path = ScanSettings::Path::kRaster;
    s.raster = *raster;
    require_axis("scan.fast_axis", raster->fast_axis, axes);
    require_axis("scan.slow_axis", raster->slow_axis, axes);
    RasterSpec checked = *raster;  // with the corners it will run with
    checked.corner_s = raster_corner_s(*raster, stage);
    checked.validate();
  } else {
    s.path = ScanSettings::Path::kLissajous;
    s.lissajous = std::get<LissajousSpec>(path);
    for (std::size_t i = 0; i < kScanAxes; ++i) {
      if (static_cast<int>(i) >= axes && s.lissajous.amplitude_m[i] != 0.0) {
        require_axis("scan.amplitude_m", static_cast<int>(i), axes);
      }
    }
    s.lissajous.validate();
  }
  return s;
}

}  // namespace hystloop
