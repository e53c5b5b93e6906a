#include "lcm/sensor_block_repair.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "lcm/blocks.hpp"
#include "lcm/message_checks.hpp"

namespace hystloop {
namespace {

constexpr std::int32_t kSaturated = sensor_block_t::SATURATED;
constexpr std::int32_t kSensorFault = sensor_block_t::SENSOR_FAULT;

bool allowed(double v, double bound) noexcept { return std::isfinite(v) && std::abs(v) <= bound; }

// The nearest value within +-bound; `fallback` for NaN.
double clamp_or(double v, double bound, double fallback) noexcept {
  return std::isnan(v) ? fallback : std::clamp(v, -bound, bound);
}

}  // namespace

SensorRepair SensorBlockRepair::repair(sensor_block_t& b) noexcept {
  SensorRepair r;
  if (b.buffer_depth_ticks < 0) {
    b.buffer_depth_ticks = 0;
    r.buffer_depth = true;
  }
  const std::size_t n =
      std::min({b.u_V.size(), b.u_ff_V.size(), b.u_fb_V.size(), b.y_ref_m.size(), b.y_m.size(), b.flags.size()});
  const std::size_t axes = axes_of(b);
  std::size_t counted_tick = n;  // the last tick counted in r.ticks (n: none yet)
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t axis = i % axes;  // tick-major: the values of one tick, axis by axis
    bool replaced = false;
    std::int32_t& flags = b.flags[i];
    if (flags < 0 || (flags & ~kKnownSampleFlags) != 0) {
      flags &= kKnownSampleFlags;
      ++r.flag_words;
      replaced = true;
    }
    double* const voltages[] = {&b.u_V[i], &b.u_ff_V[i], &b.u_fb_V[i]};
    for (std::size_t v = 0; v < 3; ++v) {
      double& u = *voltages[v];
      if (allowed(u, kMaxAbsVoltage_V)) continue;
      u = clamp_or(u, kMaxAbsVoltage_V, v == 0 ? last_u_V_[axis] : 0.0);
      flags |= kSaturated;
      ++r.voltages;
      replaced = true;
    }
    if (!allowed(b.y_m[i], kMaxAbsPosition_m)) {
      b.y_m[i] = last_y_m_[axis];
      flags |= kSensorFault;
      ++r.positions;
      replaced = true;
    }
    if (!std::isnan(b.y_ref_m[i]) && !allowed(b.y_ref_m[i], kMaxAbsPosition_m)) {
      b.y_ref_m[i] = std::nan("");
      ++r.references;
      replaced = true;
    }
    last_u_V_[axis] = b.u_V[i];
    last_y_m_[axis] = b.y_m[i];
    if (replaced && i / axes != counted_tick) {
      counted_tick = i / axes;
      ++r.ticks;
    }
  }
  return r;
}

}  // namespace hystloop
