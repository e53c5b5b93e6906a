#include "bridge/bridge_health.hpp"

#include <spdlog/fmt/fmt.h>

#include "hystloop/service_status_t.hpp"
#include "models/axis_coupling.hpp"

namespace hystloop {

BridgeHealth assess_bridge_health(const BridgeHealthInput& in) {
  BridgeHealth h;
  h.state = service_status_t::HEALTHY;
  if (in.stopping) {
    h.state = service_status_t::STOPPING;
    h.detail = fmt::format("stopping: {} the safe {} V", in.at_safe_voltage ? "at" : "ramping to", in.safe_u_V);
    return h;
  }
  if (!in.armed) {
    h.state = service_status_t::SAFE;
    h.detail = in.safe_reason;
    return h;
  }
  const auto degraded = [&h](const std::string& reason) {
    h.state = service_status_t::DEGRADED;
    h.detail += (h.detail.empty() ? "" : "; ") + reason;
  };
  if (in.late_fraction > in.degraded_late_fraction) {
    degraded(
        fmt::format("late fraction {:.3g} % > {:.3g} %", 100.0 * in.late_fraction, 100.0 * in.degraded_late_fraction));
  }
  if (in.samples_dropped > 0) {
    degraded(fmt::format("{} samples dropped: the I/O thread fell behind", in.samples_dropped));
  }
  if (in.samples_repaired > 0) {
    degraded(
        fmt::format("{} samples held values no message may carry (a servo or a sensor gone wild): recorded "
                    "with them replaced and flagged (sensor_ticks_repaired)",
                    in.samples_repaired));
  }
  if (in.samples_unpublished > 0) {
    degraded(fmt::format("{} samples could not be published: missing from the record (sensor_ticks_unpublished)",
                         in.samples_unpublished));
  }
  if (in.commands_too_far_ahead > 0) {
    degraded(
        fmt::format("{} commands refused for ticks more than {} s ahead of the bridge's clock "
                    "(bridge.max_lead_s; rejected_future): a compensator.horizon_s beyond it, or a sensor "
                    "stream the bridge did not send",
                    in.commands_too_far_ahead, in.max_lead_s));
  }
  if (in.ticks_skipped > 0) {
    degraded(
        fmt::format("{} ticks ({:.3g} ms) skipped this period: the bridge's own clock fell behind and the outputs "
                    "held stale voltages (ticks_skipped; real time on this host: docs/TIMING.md)",
                    in.ticks_skipped, static_cast<double>(in.ticks_skipped) * in.dt_s * 1e3));
  }
  // A clamped command is not what the compensator and the servo asked for: the rig tracks worse
  // than its figures say, whatever else is well.
  const ClampCounts& c = in.clamped_last_second;
  if (c.either > 0) {
    degraded(fmt::format("{} ticks clamped in the last second (range {}, slew {})", c.either, c.range, c.slew));
  }
  return h;
}

std::string position_reason(int axis, double y_m, const ActuatorLimits& limits, int axes, std::int64_t tick) {
  const bool above = y_m > limits.position_max_m;
  const std::string key = axis_field(above ? "actuator.position_max_m" : "actuator.position_min_m", axis);
  return fmt::format(
      "{}'s measured position {:.4g} um beyond {} {:.4g} um for {} ticks: {} to the safe state at tick {}; re-arm "
      "via HX_CONTROL",
      axis_name(axis), y_m * 1e6, key, (above ? limits.position_max_m : limits.position_min_m) * 1e6,
      ActuatorLimits::kPositionLimitTicks, axes > 1 ? "every axis" : "the actuator", tick);
}

std::string oscillation_reason(int axis, double hz, double rms_V, const OscillationLimit& limit, int axes,
                               std::int64_t tick) {
  return fmt::format(
      "{}'s servo oscillates at {:.0f} Hz: its output {:.3g} V RMS above {:g} Hz for {:g} ms, beyond "
      "bridge.oscillation_rms_V {:g} V: {} to the safe state at tick {} (its gains or notch do not suit the stage: "
      "hystloop-ctl gains --stage-config checks them); re-arm via HX_CONTROL",
      axis_name(axis), hz, rms_V, limit.above_hz, limit.hold_s * 1e3, limit.rms_V,
      axes > 1 ? "every axis" : "the actuator", tick);
}

std::string stall_reason(std::uint64_t skipped_ticks, double max_stall_s, double rate_hz, std::int64_t tick) {
  return fmt::format(
      "the bridge's own clock stalled: {} ticks ({:.3g} ms) skipped within one second, beyond bridge.max_stall_s "
      "{} s: the outputs held stale voltages; every axis to the safe state at tick {} (real time on this host: "
      "docs/TIMING.md); re-arm via HX_CONTROL",
      skipped_ticks, static_cast<double>(skipped_ticks) / rate_hz * 1e3, max_stall_s, tick);
}

std::string watchdog_reason(const DryBufferFigures& f) {
  std::string why;
  const auto add = [&why](const std::string& what) { why += (why.empty() ? "" : "; ") + what; };
  if (f.command_after_trip) {
    add("command blocks kept arriving after it: too late for their ticks (stale)");
  } else if (f.since_last_command_s < 0.0) {
    add("no command block received since the start");
  } else {
    add(fmt::format("the last command block arrived {:.1f} ms before", f.since_last_command_s * 1e3));
  }
  if (f.commands_rejected > 0) {
    add(fmt::format("{} HX_COMMAND message(s) refused in the last {:.3g} s ({:.3g}/s; see command.rejected_*)",
                    f.commands_rejected, f.period_s,
                    f.period_s > 0.0 ? static_cast<double>(f.commands_rejected) / f.period_s : 0.0));
  }
  if (f.command_queue_full > 0) {
    add(fmt::format("{} command ticks found the real-time queue full (command_queue_full)", f.command_queue_full));
  }
  add(fmt::format("the I/O thread's longest pass {:.1f} ms, longest wait {:.1f} ms", f.io_longest_pass_s * 1e3,
                  f.io_longest_wait_s * 1e3));
  return fmt::format(
      "watchdog: no command buffered for more than {} s{}, tripped at tick {} ({}){}; re-arm via "
      "HX_CONTROL",
      f.watchdog_s, f.axes > 1 && f.tripped_by >= 0 ? fmt::format(" on {}", axis_name(f.tripped_by)) : std::string(),
      f.trip_tick, why, f.axes > 1 ? ", every axis to the safe state" : "");
}

}  // namespace hystloop
