// The compensator service's HX_STATUS report: its counters, the axes' laws' and the state with
// its reasons, and the log lines of sequence events.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string_view>

#include <spdlog/spdlog.h>

#include "compensator/compensator_service.hpp"
#include "runtime/stage_config.hpp"
#include "compensator/scan_message.hpp"
#include "compensator/trajectory_message.hpp"
#include "core/clock.hpp"
#include "core/periodic_timer.hpp"
#include "core/process.hpp"
#include "lcm/blocks.hpp"
#include "lcm/feedforward_mode.hpp"
#include "lcm/status_counters.hpp"
#include "models/model_descriptors.hpp"

namespace hystloop {

CounterSet::Entries CompensatorService::collect_counters() const {
  CompensatorCounters c = retired_;
  for (int a = 0; a < settings_.axes; ++a) c += laws_[static_cast<std::size_t>(a)]->counters();
  const CompensatorServiceCounters& s = counters_;
  // The plan's counters, each axis's summed (samples: every axis's), as CompensatorCounters lists
  // them; the sets refused before they reached a law count with those the laws rejected.
  c.params_rejected += s.params_refused;
  CounterSet::Entries entries;
  CompensatorCounters::for_each([&](const char* name, auto field) { entries.emplace_back(name, c.*field); });
  entries.insert(entries.end(), {{"command_blocks_published", s.command_blocks_published},
                                 {"command_ticks_published", s.command_ticks_published},
                                 {"sensor_blocks_wrong_axes", s.sensor_blocks_wrong_axes},
                                 {"params_invalid", s.params_invalid},
                                 {"params_stale", s.params_stale},
                                 {"params_stale_repeat", s.params_stale_repeat},
                                 {"params_stale_below", s.params_stale_below},
                                 {"model_unknown_kind", s.model_unknown_kind},
                                 {"model_unknown_format", s.model_unknown_format},
                                 {"trajectories", s.trajectories},
                                 {"trajectory_repeats", s.trajectory_repeats},
                                 {"trajectory_refused", s.trajectory_refused},
                                 {"trajectory_late_start", s.trajectory_late_start},
                                 {"control_acted", s.control_acted},
                                 {"control_refused", s.control_refused},
                                 {"bridge_restarts", s.bridge_restarts},
                                 {"sensor_jumps", guard_.counters().jumps},
                                 {"sensor_jumps_ignored", guard_.counters().ignored},
                                 {"sensor_blocks_held", guard_.counters().held},
                                 {"params_publishers_evicted", admission_.evictions()},
                                 {"log_lines_suppressed", log_limiter_.suppressed_total()}});
  // Scans and what named an axis this stage lacks (a one-axis stage counts them too); with several
  // axes these say how the axes planned together.
  entries.emplace_back("scans", s.scans);
  entries.emplace_back("scans_refused", s.scans_refused);
  entries.emplace_back("wrong_axis", s.wrong_axis);
  if (settings_.axes > 1) {
    entries.emplace_back("axes", static_cast<std::uint64_t>(settings_.axes));
    entries.emplace_back("plan_mismatch", s.plan_mismatch);
  }
  return entries;
}

// Off the sensor path: what the SequenceGuard decided since the last line of each kind. Forged
// blocks can make these at every report, so each kind goes through the limiter; the count
// since the last line written is kept until one is.
void CompensatorService::log_sequence_events() {
  const SequenceGuard::Counters& g = guard_.counters();
  constexpr int kHeld = SequenceGuard::kConfirmBlocks - 1;
  const std::int64_t now_ns = monotonic_ns();
  if (g.restarts != restarts_logged_) {
    if (const LogLimiter::Gate gate = log_limiter_.allow(kLogSensorRestart, now_ns)) {
      const Discontinuity& d = discontinuities_.last_restart();
      spdlog::warn(
          "bridge restart: sensor ticks went back: tick {} was expected, the stream continues from tick {} "
          "(confirmed by {} blocks, the first {} of them held): control law restarted ({} restarts in all){}",
          d.expected_tick, d.resumed_tick, SequenceGuard::kConfirmBlocks, kHeld, g.restarts, suppressed_note(gate));
      restarts_logged_ = g.restarts;
    }
  }
  if (g.jumps != jumps_logged_) {
    if (const LogLimiter::Gate gate = log_limiter_.allow(kLogSensorJump, now_ns)) {
      const Discontinuity& d = discontinuities_.last_jump();
      spdlog::warn(
          "sensor ticks jumped ahead: tick {} was expected, the stream continues from tick {} (confirmed by {} "
          "blocks, the first {} of them held; {} jumps in all){}",
          d.expected_tick, d.resumed_tick, SequenceGuard::kConfirmBlocks, kHeld, g.jumps, suppressed_note(gate));
      jumps_logged_ = g.jumps;
    }
  }
  if (g.ignored != ignored_logged_) {
    if (const LogLimiter::Gate gate = log_limiter_.allow(kLogSensorIgnored, now_ns)) {
      spdlog::warn(
          "{} jump(s) or restart(s) of the sensor ticks not believed since the last such line: not confirmed "
          "by the blocks that followed (a forged or corrupted block?); sensor_jumps_ignored {}, "
          "sensor_blocks_held {} in all{}",
          g.ignored - ignored_logged_, g.ignored, g.held, suppressed_note(gate));
      ignored_logged_ = g.ignored;
    }
  }
}

bool CompensatorService::report_if_due() noexcept {
  if (!verdict_due_ || !status_.immediate_allowed(monotonic_ns())) return false;
  try {
    report(wall_utime(), false, false);
  } catch (...) {  // the periodic report says it within a second
    verdict_due_ = false;
    return false;
  }
  return true;
}

void CompensatorService::report(std::int64_t utime, bool stopping, bool end_period) {
  verdict_due_ = false;
  log_sequence_events();
  const auto counters = collect_counters();
  const Compensator& c = x();
  if (c.counters().params_swapped != swaps_reported_) {
    swaps_reported_ = c.counters().params_swapped;
    spdlog::info("parameters v{} in use: {}", c.params_version(), describe_model(c.model_params()));
  }

  std::int8_t state = service_status_t::HEALTHY;
  std::string detail;
  if (stopping) {
    state = service_status_t::STOPPING;
    detail = "stopping; ";
  } else if (!have_sample_) {
    state = service_status_t::STARTING;
    detail = "waiting for samples; ";
  } else if (blocks_in_period_ == 0) {
    state = service_status_t::DEGRADED;
    detail = "no samples from the bridge this period; ";
  }
  // Every axis's clamps and experiments: one axis clamped makes the stage's tracking degraded.
  std::uint64_t u_clamped = 0, u_slew_clamped = 0;
  int experimenting = -1;  // an axis running an experiment, -1: none
  for (int a = 0; a < settings_.axes; ++a) {
    const Compensator& law = *laws_[static_cast<std::size_t>(a)];
    u_clamped += law.counters().u_clamped;
    u_slew_clamped += law.counters().u_slew_clamped;
    if (experimenting < 0 && law.experiment_running()) experimenting = a;
  }
  const std::uint64_t clamped = (u_clamped - clamped_reported_) + (u_slew_clamped - slew_clamped_reported_);
  if (end_period) {
    clamped_in_period_ = clamped;
    clamped_reported_ = u_clamped;
    slew_clamped_reported_ = u_slew_clamped;
  }
  if (state == service_status_t::HEALTHY && clamped_in_period_ > 0) {
    state = service_status_t::DEGRADED;
    detail += fmt::format("feedforward clamped at the actuator's limits on {} ticks in the last second; ",
                          clamped_in_period_);
  }
  ParamsAdmission::FrozenList frozen;
  const std::size_t n_frozen = admission_.frozen(monotonic_ns(), frozen);
  if (n_frozen > 0 && (state == service_status_t::HEALTHY || state == service_status_t::DEGRADED)) {
    state = service_status_t::DEGRADED;
    for (std::size_t i = 0; i < n_frozen; ++i) {
      const ParamsAdmission::Frozen& f = frozen[i];
      detail += fmt::format(
          "parameter sets from publisher {:x} refused as stale: {} in a row below v{} accepted from it before, the "
          "last v{}; none of its sets is used now (params v{} in use; params_stale_below); ",
          static_cast<std::uint64_t>(f.publisher), f.refusals, f.accepted_version, f.refused_version,
          c.params_version());
    }
  }
  // A line whose learning the monitor stopped tracks on its best table (or none), no worse than
  // without learning, but not as the learning would: degraded, with the reason, until the line is
  // restarted, reset or learning is turned on again.
  for (int a = 0; a < settings_.axes; ++a) {
    const LearnerFigures& l = laws_[static_cast<std::size_t>(a)]->learner().figures();
    if (!l.diverged) continue;
    if (state == service_status_t::HEALTHY) state = service_status_t::DEGRADED;
    detail += fmt::format(
        "learning stopped{}: it made the line's error worse than without (a period at more than {} x the {:.3g} nm "
        "RMS without learning), {}; ",
        settings_.axes > 1 ? fmt::format(" on {}", axis_name(a)) : std::string(), c.config().learning.monitor_ratio,
        l.baseline_rms_m * 1e9, l.holding ? "its best period's corrections held" : "its correction faded out");
  }
  const MemParams& m = c.mem_params();
  detail += fmt::format("mode {}, params v{} c1={:.6g} c2={:.6g} c3={:.6g}, planning {} ticks ahead{}",
                        to_string(c.experiment_running() ? FeedforwardMode::kExperiment : c.mode()), c.params_version(),
                        m.c1, m.c2, m.c3, c.config().horizon_ticks,
                        experimenting < 0    ? std::string()
                        : settings_.axes > 1 ? fmt::format(", experiment running on {}", axis_name(experimenting))
                                             : std::string(", experiment running"));
  if (c.stage().has_dynamics()) detail += "; stage " + describe_stage(c.stage(), c.config().dt_s);
  const LearnerFigures& learner = c.learner().figures();
  if (learner.active) {
    detail += fmt::format("; learning a {}-tick period ({} periods learned, last {:.3g} nm RMS)", learner.period_ticks,
                          learner.periods_learned, learner.last_error_rms_m * 1e9);
  }
  for (int a = 1; a < settings_.axes; ++a) {  // the other axes' sets and learning, each in a few words
    const Compensator& law = *laws_[static_cast<std::size_t>(a)];
    const MemParams& am = law.mem_params();
    const LearnerFigures& al = law.learner().figures();
    detail += fmt::format(
        "; {}: params v{} c1={:.6g} c2={:.6g} c3={:.6g}{}", axis_name(a), law.params_version(), am.c1, am.c2, am.c3,
        al.active
            ? fmt::format(", learning ({} periods, last {:.3g} nm RMS)", al.periods_learned, al.last_error_rms_m * 1e9)
            : std::string());
  }
  if (!verdict_.empty() && monotonic_ns() < verdict_until_ns_) detail += "; " + verdict_;
  if (const std::string note = acks_.refusal_note(utime); !note.empty()) detail += "; " + note;
  status_.begin(state, detail);
  reported_.report(status_, counters);
  std::uint64_t semantic_rejects = 0;
  for (const char* name : {"params_rejected", "params_invalid", "model_unknown_kind", "model_unknown_format",
                           "trajectory_refused", "control_refused", "sensor_blocks_wrong_axes"}) {
    for (const auto& [n, value] : counters) {
      if (n == name) semantic_rejects += reported_.since(n, value);
    }
  }
  // Versions and tick distances below 0 (none yet) are reported as 0: the counters are unsigned.
  const auto at_least_0 = [](std::int64_t v) { return static_cast<std::uint64_t>(std::max<std::int64_t>(0, v)); };
  status_.counter("trajectory_version", at_least_0(counters_.trajectory_version));
  status_.counter("trajectory_refused_version", at_least_0(counters_.trajectory_refused_version));
  status_.counter("trajectory_shaped_version", at_least_0(counters_.trajectory_shaped_version));
  acks_.report(status_);
  status_.counter("mode", static_cast<std::uint64_t>(c.mode()));  // the tracking mode (command_block_t.MODE_*)
  status_.counter("params_version", at_least_0(c.params_version()));
  for (int a = 1; a < settings_.axes; ++a) {  // the other axes' sets: hystloop-ctl params --axis waits on them
    status_.counter(axis_params_counter_[static_cast<std::size_t>(a)],
                    at_least_0(laws_[static_cast<std::size_t>(a)]->params_version()));
  }
  // Learning per axis: x's under the one-axis names, the others' behind their axis (y_learning_active, ...).
  for (int a = 0; a < settings_.axes; ++a) {
    const Compensator& law = *laws_[static_cast<std::size_t>(a)];
    const LearnerFigures& l = law.learner().figures();
    const std::string p = a == 0 ? std::string() : std::string(axis_name(a)) + "_";
    status_.counter(p + "learning_active", l.active ? 1u : 0u);
    status_.counter(p + "learning_periods", l.periods_learned);
    status_.counter(p + "learning_divergences", l.divergences);
    status_.counter(p + "params_held_by_learning", law.params_held_by_learning() ? 1u : 0u);
    status_.counter(p + "learning_rms_pm", static_cast<std::uint64_t>(std::llround(l.last_error_rms_m * 1e12)));
  }
  if (c.next_tick() >= 0) status_.counter("plan_ahead_ticks", at_least_0(c.next_tick() - 1 - c.last_seq()));
  reported_.report(status_, "sensor", samples_.counters());
  reported_.report(status_, "trajectory", trajectories_.counters());
  reported_.report(status_, "scan", scans_.counters());
  reported_.report(status_, "params", params_.counters());
  reported_.report(status_, "model", models_.counters());
  reported_.report(status_, "control", control_.counters());
  reported_.report(status_, "command", command_pub_.counters());
  status_.add_rejected(static_cast<std::int64_t>(semantic_rejects));
  status_.loop_timing(work_);
  status_.latency(latency_);
  status_.publish(utime);
  if (!end_period) return;
  latency_total_.merge(latency_);
  latency_.reset();
  work_.reset();
  blocks_in_period_ = 0;
}

}  // namespace hystloop
