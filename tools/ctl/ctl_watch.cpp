#include "ctl_watch.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "ctl_health.hpp"
#include "lcm/blocks.hpp"

namespace hystloop::ctl {

void WatchSecond::add_error(double e_m) noexcept {
  ++tracking;
  sum_sq_m2 += e_m * e_m;
  max_abs_m = std::max(max_abs_m, std::abs(e_m));
}

void WatchSecond::add_sensor_block(const sensor_block_t& block) noexcept {
  bool armed = true;
  for_each_tick(block, [&](const SensorTick& t) {
    ++samples;
    if (std::isfinite(t.y_ref_m)) add_error(t.y_ref_m - t.y_m);
    armed = armed && (t.flags & sensor_block_t::SAFE_STATE) == 0;
  });
  if (armed) buffer_min_ticks = std::min(buffer_min_ticks.value_or(block.buffer_depth_ticks), block.buffer_depth_ticks);
}

std::optional<double> WatchSecond::rms_m() const noexcept {
  if (tracking == 0) return std::nullopt;
  return std::sqrt(sum_sq_m2 / static_cast<double>(tracking));
}

std::optional<double> learning_rms_nm(const service_status_t& compensator) {
  if (const auto nm = find_counter(compensator, "learning_rms_nm")) return static_cast<double>(*nm);
  if (const auto pm = find_counter(compensator, "learning_rms_pm")) return static_cast<double>(*pm) * 1e-3;
  return std::nullopt;
}

std::string format_watch_line(const WatchLine& l) {
  char buf[320];
  std::string out;
  std::snprintf(buf, sizeof buf, "%5.0f s", l.elapsed_s);
  out += buf;
  if (const auto rms = l.second.rms_m()) {
    std::snprintf(buf, sizeof buf, "  rms %7.1f nm  max %7.1f nm", *rms * 1e9, l.second.max_abs_m * 1e9);
  } else {
    std::snprintf(buf, sizeof buf, "  rms %7s nm  max %7s nm", "--", "--");
  }
  out += buf;
  std::snprintf(buf, sizeof buf, "  ticks %6llu/%llu", static_cast<unsigned long long>(l.second.tracking),
                static_cast<unsigned long long>(l.second.samples));
  out += buf;
  out += l.params_in_use ? "  params v" + std::to_string(*l.params_in_use) : std::string("  params --");
  if (l.params_latest && l.params_latest != l.params_in_use)
    out += " (v" + std::to_string(*l.params_latest) + " published)";
  if (l.late_total) {
    std::snprintf(buf, sizeof buf, "  late %lld (+%lld)", static_cast<long long>(*l.late_total),
                  static_cast<long long>(l.late_delta.value_or(0)));
    out += buf;
  } else {
    out += "  late --";
  }
  out += l.clamped_per_s ? "  clamped " + std::to_string(*l.clamped_per_s) + "/s" : std::string("  clamped --");
  out += l.second.buffer_min_ticks ? "  buf min " + std::to_string(*l.second.buffer_min_ticks)
                                   : std::string("  buf min --");
  out += l.bridge_state.empty() ? "  bridge --" : "  bridge " + l.bridge_state;
  if (l.learning_rms_nm || l.learning_periods) {
    if (l.learning_rms_nm) {
      std::snprintf(buf, sizeof buf, "  learned %.1f nm", *l.learning_rms_nm);
    } else {
      std::snprintf(buf, sizeof buf, "  learned -- nm");
    }
    out += buf;
    out += " (" + (l.learning_periods ? std::to_string(*l.learning_periods) : std::string("--")) + " periods)";
  }
  const std::int64_t refused = l.trajectories_refused.value_or(0), shaped = l.trajectories_shaped.value_or(0);
  if (refused > 0 || shaped > 0) {
    out += "  trajectories refused " + std::to_string(refused) + ", shaped " + std::to_string(shaped);
  }
  return out;
}

}  // namespace hystloop::ctl
