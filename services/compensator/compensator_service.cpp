#include "compensator/compensator_service.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <string_view>

#include <spdlog/spdlog.h>

#include "compensator/scan_message.hpp"
#include "compensator/trajectory_message.hpp"
#include "core/clock.hpp"
#include "core/periodic_timer.hpp"
#include "core/process.hpp"
#include "lcm/blocks.hpp"
#include "lcm/status_counters.hpp"
#include "lcm/feedforward_mode.hpp"
#include "models/model_descriptors.hpp"
#include "runtime/io_loop.hpp"

namespace hystloop {

CompensatorCounters& operator+=(CompensatorCounters& a, const CompensatorCounters& b) noexcept {
  a.samples += b.samples;
  a.out_of_order += b.out_of_order;
  a.gaps += b.gaps;
  a.planned += b.planned;
  a.ticks_behind += b.ticks_behind;
  a.params_accepted += b.params_accepted;
  a.params_rejected += b.params_rejected;
  a.params_swapped += b.params_swapped;
  a.reversals += b.reversals;
  a.nonfinite_outputs += b.nonfinite_outputs;
  a.model_switches += b.model_switches;
  a.reanchors += b.reanchors;
  a.reanchors_skipped += b.reanchors_skipped;
  a.u_clamped += b.u_clamped;
  a.u_slew_clamped += b.u_slew_clamped;
  a.learning_held += b.learning_held;
  a.trajectories_refused += b.trajectories_refused;
  a.trajectories_shaped += b.trajectories_shaped;
  a.stage_swaps += b.stage_swaps;
  a.experiment_ramped += b.experiment_ramped;
  return a;
}

namespace {

// Consecutive blocks of a new numbering whose sample times (utime) are further apart than this
// are not one stream [us].
constexpr std::int64_t kConfirmWindowUs = 100'000;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// HX_MODEL: an unknown kind or format version reaches on_model, which counts it by its reason.
Subscription<model_params_t>::Options model_envelope() {
  Subscription<model_params_t>::Options o;
  o.check = &check_model_params_envelope;
  return o;
}

// Axis a's control law (every axis configured alike); none past the stage's axes.
std::optional<Compensator> make_law(const CompensatorSettings& settings, int axis) {
  static_assert(kMaxAxes == 3, "laws_ is built one initialiser per axis");
  if (axis >= settings.axes) return std::nullopt;
  return std::optional<Compensator>(std::in_place, settings.control);
}

template <class T>
typename Subscription<T>::Options queue_of(int capacity) {
  typename Subscription<T>::Options o;
  o.queue_capacity = capacity;
  return o;
}

}  // namespace

CompensatorService::CompensatorService(const CompensatorSettings& settings, lcm::LCM& lcm, const ChannelNames& channels)
    : settings_(settings),
      lcm_(lcm),
      laws_{make_law(settings, 0), make_law(settings, 1), make_law(settings, 2)},
      command_pub_(lcm, channels.command),
      samples_(
          lcm, channels.sensor, [this](const sensor_block_t& m, std::int64_t t) { on_sensor(m, t); },
          queue_of<sensor_block_t>(settings.sample_queue_capacity)),
      trajectories_(lcm, channels.trajectory, [this](const trajectory_t& m, std::int64_t) { on_trajectory(m); }),
      scans_(lcm, channels.scan, [this](const scan_t& m, std::int64_t) { on_scan(m); }),
      params_(lcm, channels.params, [this](const mem_params_t& m, std::int64_t) { on_params(m); }),
      models_(
          lcm, channels.model, [this](const model_params_t& m, std::int64_t) { on_model(m); }, model_envelope()),
      control_(lcm, channels.control, [this](const control_t& m, std::int64_t) { on_control(m); }),
      status_(lcm, channels.status, "compensator"),
      // A block within the horizon of the next expected tick continues the stream (lost blocks
      // or a reorder: the plan still covers them); one further away must be confirmed.
      guard_(settings.control.horizon_ticks, kConfirmWindowUs) {
  reserve_storage(command_);
  for (int a = 1; a < kMaxAxes; ++a) axis_params_counter_[static_cast<std::size_t>(a)] = params_version_counter(a);
  x().set_trajectory(settings.trajectory, kNaN);  // the configured reference starts with the plan
}

void CompensatorService::on_sensor(const sensor_block_t& msg, std::int64_t recv_utime) noexcept {
  const std::int64_t start_ns = monotonic_ns();
  if (msg.n_axes != settings_.axes) {
    ++counters_.sensor_blocks_wrong_axes;
    return;
  }
  // The block's own time, not the receive time: the commands stay a function of the messages.
  // discontinuities_ notes where a confirmed jump or restart went, for log_sequence_events().
  switch (discontinuities_.check(guard_, msg.seq, msg.n_ticks, msg.utime)) {
    case SequenceGuard::Verdict::hold:  // a jump or a restart not confirmed yet: not used
      work_.add(monotonic_ns() - start_ns);
      return;
    case SequenceGuard::Verdict::restart: restart_control_law(); break;
    case SequenceGuard::Verdict::jump:
    case SequenceGuard::Verdict::take: break;
  }
  const SensorTick last = sensor_tick(msg, static_cast<std::size_t>(msg.n_ticks) - 1);
  for (int a = 0; a < settings_.axes; ++a) {
    Compensator& law = *laws_[static_cast<std::size_t>(a)];
    for_each_tick(
        msg,
        [&](const SensorTick& t) {
          law.observe({t.seq, t.u_V, t.y_m, t.u_ff_V});
        },
        static_cast<std::size_t>(a));
  }
  last_sample_utime_ = last.utime;
  ++blocks_in_period_;
  if (!have_sample_) {
    have_sample_ = true;
    if (settings_.scan.path != ScanSettings::Path::kNone && !scan_taken_) take_configured_scan();
    if (pending_trajectory_) {  // now the loop time is known
      const TrajectorySpec spec = *pending_trajectory_;
      pending_trajectory_.reset();
      try {
        apply_trajectory(spec, pending_start_utime_, pending_version_, pending_axis_);
      } catch (const std::exception& e) {
        ++counters_.trajectory_refused;
        decide_trajectory(pending_version_, e.what(), true, false);
      }
      if (verdict_due_) {
        try {
          report(wall_utime(), false, false);
        } catch (...) {  // the periodic report says it a second later
        }
      }
    }
  }
  publish_plan();
  // recv_utime is LCM's receive time on this host's clock; a value outside [0, 10 s) is not a latency.
  const std::int64_t latency_us = wall_utime() - recv_utime;
  if (latency_us >= 0 && latency_us < 10'000'000) latency_.add(latency_us * 1000);
  work_.add(monotonic_ns() - start_ns);
}

void CompensatorService::publish_plan() noexcept {
  const auto axes = static_cast<std::size_t>(settings_.axes);
  for (;;) {
    // Every law observed the same ticks, so each plans the same ones. Should they ever differ (a
    // bug), nothing is sent: a tick commanded on some axes and not others would move the stage
    // along no path; the bridge's watchdog then takes every axis to the safe state.
    const std::size_t n = x().plan(plan_[0]);
    for (std::size_t a = 1; a < axes; ++a) {
      const std::size_t m = laws_[a]->plan(plan_[a]);
      if (m != n || (n > 0 && plan_[a][0].seq != plan_[0][0].seq)) {
        ++counters_.plan_mismatch;
        return;
      }
    }
    if (n == 0) return;
    begin_block(command_, plan_[0][0].seq, wall_utime(), x().last_seq(), settings_.axes);
    std::array<CommandTick, kMaxAxes> tick{};
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t a = 0; a < axes; ++a) tick[a] = plan_[a][i];
      append_tick(command_, std::span<const CommandTick>(tick).first(axes));
    }
    if (command_pub_.publish(command_)) {
      ++counters_.command_blocks_published;
      counters_.command_ticks_published += n;
    }
  }
}

void CompensatorService::take_configured_scan() {
  scan_taken_ = true;
  const double start_s = static_cast<double>(x().last_seq()) * x().config().dt_s + settings_.scan.start_after_s;
  try {
    spdlog::info("{}", take_scan(settings_.scan, start_s));
  } catch (const std::exception& e) {
    spdlog::error("the configured scan was refused: {}", e.what());
  }
}

std::string CompensatorService::take_scan(const ScanSettings& scan, double start_s) {
  try {
    // One corner for every axis (x's stage model decides it): the axes run one path.
    const double corner_s = raster_corner_s(scan.raster, x().stage());
    const double check_s = scan_check_s(scan, corner_s);
    if (check_s * settings_.axes > kScanCheckBudget_s) {
      throw ParameterError("scan", fmt::format("runs {:.3g} s on each of {} axes; a scan is checked whole before it is "
                                               "taken, on the compensator's one thread, at most {} s of loop time over "
                                               "all axes (the bridge holds {} s of commands meanwhile): split it",
                                               check_s, settings_.axes, kScanCheckBudget_s,
                                               static_cast<double>(x().config().horizon_ticks) * x().config().dt_s));
    }
    std::vector<ScanShare> shares;
    std::vector<Compensator*> laws;
    for (int a = 0; a < settings_.axes; ++a) {
      shares.push_back(scan_share(scan, settings_.decoupling, a, start_s, corner_s));
      laws.push_back(&*laws_[static_cast<std::size_t>(a)]);
    }
    take_scan_on_every_axis(laws, shares, scan.blend_s);
    ++counters_.scans;
    return fmt::format("scan taken by {} axes{}: from loop time {:.4f} s to {:.4f} s", settings_.axes,
                       scan.decouple && settings_.axes > 1 ? ", decoupled" : "", start_s, shares[0].end_s());
  } catch (...) {
    ++counters_.scans_refused;
    throw;
  }
}

bool CompensatorService::scan_running() const noexcept {
  for (int a = 0; a < settings_.axes; ++a) {
    const Compensator& c = *laws_[static_cast<std::size_t>(a)];
    const double next_s = static_cast<double>(std::max<std::int64_t>(c.next_tick(), 0)) * c.config().dt_s;
    if (c.scan() != nullptr && next_s < c.scan()->end_s()) return true;
  }
  return false;
}

void CompensatorService::on_scan(const scan_t& msg) {
  if (msg.version == trajectory_version_ || msg.version == refused_version_) {  // UDP repeats: decided once
    ++counters_.trajectory_repeats;
    return;
  }
  try {
    if (!have_sample_) {
      throw ParameterError("scan", "no sensor block yet: where the axes are, and the loop time, are not known");
    }
    const ScanSettings scan = scan_from_message(msg, settings_.axes, x().stage());
    const Compensator& c = x();
    const double dt_s = c.config().dt_s;
    const double earliest_s = static_cast<double>(std::max<std::int64_t>(c.next_tick(), 0)) * dt_s + scan.blend_s;
    const double start_s =
        msg.start_utime == 0 ? earliest_s : loop_time_of_utime(msg.start_utime, last_sample_utime_, c.last_seq(), dt_s);
    const std::string note = take_scan(scan, start_s);
    trajectory_version_ = msg.version;
    ++counters_.trajectories;
    decide_trajectory(msg.version, note, false, false);
    if (const LogLimiter::Gate g = log_limiter_.allow(kLogTrajectory, monotonic_ns())) {
      spdlog::info("scan v{}: {}{}", msg.version, note, suppressed_note(g));
    }
  } catch (const std::exception& e) {
    ++counters_.trajectory_refused;
    refused_version_ = msg.version;
    decide_trajectory(msg.version, e.what(), true, false);
    if (const LogLimiter::Gate g = log_limiter_.allow(kLogTrajectoryRefused, monotonic_ns())) {
      spdlog::warn("scan v{} refused: {}{}", msg.version, escape_wire(e.what(), 600), suppressed_note(g));
    }
  }
  if (verdict_due_) report(wall_utime(), false, false);
}

Compensator& CompensatorService::law(int axis, const char* field) {
  if (axis < 0 || axis >= settings_.axes) {
    ++counters_.wrong_axis;
    throw ParameterError(field, "names axis " + std::string(axis_name(axis)) + ", but this stage has " +
                                    (settings_.axes == 1 ? std::string("only x (compensator.axes 1)")
                                                         : std::to_string(settings_.axes) + " axes"));
  }
  return *laws_[static_cast<std::size_t>(axis)];
}

void CompensatorService::apply_trajectory(const TrajectorySpec& spec, std::int64_t start_utime, std::int64_t version,
                                          int axis) {
  Compensator& c = law(axis, "trajectory.axis");
  if (settings_.axes > 1 && scan_running()) {
    // One axis leaving the path would leave the others following their shares of a motion that no
    // longer happens (each share holds the others' coupling).
    throw ParameterError("trajectory", "a scan is running on every axis: wait for its end (or send a scan)");
  }
  TrajectoryVerdict v;
  if (start_utime == 0) {
    v = c.take_trajectory(spec, kNaN);
    pending_trajectory_.reset();  // a newer trajectory replaces one waiting for the first sample
  } else if (!have_sample_) {
    spec.validate();
    pending_trajectory_ = spec;
    pending_start_utime_ = start_utime;
    pending_version_ = version;
    pending_axis_ = axis;
    return;
  } else {
    const double start_s = loop_time_of_utime(start_utime, last_sample_utime_, c.last_seq(), c.config().dt_s);
    v = c.take_trajectory(spec, start_s);
    if (!v.started) ++counters_.trajectory_late_start;
  }
  ++counters_.trajectories;
  decide_trajectory(version, v.note, false, v.shaped);
}

void CompensatorService::decide_trajectory(std::int64_t version, const std::string& verdict, bool refused,
                                           bool shaped) {
  if (version <= 0) return;  // the configured reference: nobody waits for it
  if (refused) {
    counters_.trajectory_refused_version = version;
    // The compensator's own words (the limit, what would fit): whole, not cut like wire text.
    constexpr std::size_t kVerdictChars = 600;
    verdict_ = fmt::format("trajectory {} refused: {}", version, escape_wire(verdict, kVerdictChars));
  } else {
    counters_.trajectory_version = version;
    if (shaped) counters_.trajectory_shaped_version = version;
    verdict_ = verdict.empty() ? std::string()
                               : fmt::format("trajectory {} {}: {}", version, shaped ? "shaped" : "taken", verdict);
  }
  verdict_until_ns_ = monotonic_ns() + 10'000'000'000;  // 10 s in the status detail
  verdict_due_ = true;                                  // answered at once, not at the next second
}

void CompensatorService::on_trajectory(const trajectory_t& msg) {
  if (msg.version == trajectory_version_ || msg.version == refused_version_) {  // UDP repeats: decided once
    ++counters_.trajectory_repeats;
    return;
  }
  try {
    apply_trajectory(trajectory_from_message(msg), msg.start_utime, msg.version, msg.axis);
    trajectory_version_ = msg.version;
    if (const LogLimiter::Gate g = log_limiter_.allow(kLogTrajectory, monotonic_ns())) {
      spdlog::info("trajectory v{}: shape {}, amplitude {:.4g} m, offset {:.4g} m, {} Hz, blend {} s{}", msg.version,
                   msg.shape, msg.amplitude_m, msg.offset_m, msg.frequency_Hz, msg.blend_s, suppressed_note(g));
      if (!verdict_.empty()) spdlog::info("{}", verdict_);
    }
  } catch (const std::exception& e) {
    ++counters_.trajectory_refused;
    refused_version_ = msg.version;  // its repeats are the same refusal
    decide_trajectory(msg.version, e.what(), true, false);
    if (const LogLimiter::Gate g = log_limiter_.allow(kLogTrajectoryRefused, monotonic_ns())) {
      spdlog::warn("trajectory v{} refused: {}{}", msg.version, escape_wire(e.what(), 600), suppressed_note(g));
    }
  }
  if (verdict_due_) report(wall_utime(), false, false);
}

void CompensatorService::on_control(const control_t& msg) {
  if (!filter_.accept(msg)) return;
  auto refuse = [&](const std::string& why) {
    ++counters_.control_refused;
    acks_.refused(msg.request_id, why, wall_utime());
    verdict_due_ = true;  // its sender waits for the answer
    if (const LogLimiter::Gate g = log_limiter_.allow(kLogControlRefused, monotonic_ns())) {
      spdlog::warn("control request {} (command {}) refused: {}{}", msg.request_id, msg.command, escape_wire(why),
                   suppressed_note(g));
    }
  };
  // What a request did is logged too, at most once a second (the next line says how many were not).
  auto acted = [&] { return log_limiter_.allow(kLogControl, monotonic_ns()); };
  try {
    switch (msg.command) {
      case control_t::SET_MODE: {
        const auto mode = feedforward_mode_from_wire(msg.mode);
        if (!mode || *mode == FeedforwardMode::kExperiment) {
          return refuse("mode " + std::to_string(msg.mode) + " is not selectable (" + selectable_mode_choices() + ")");
        }
        for_each_law([&](Compensator& c) { c.set_mode(*mode); });
        if (const LogLimiter::Gate g = acted()) {
          spdlog::info("mode {} (request {}){}", to_string(x().mode()), msg.request_id, suppressed_note(g));
        }
        break;
      }
      case control_t::START_EXPERIMENT: {
        const ExperimentSpec e =
            make_experiment_spec(msg.experiment, msg.experiment_amplitude_V, msg.experiment_offset_V,
                                 msg.experiment_frequency_Hz, msg.experiment_duration_s);
        Compensator& driven = law(msg.axis, "control.axis");
        if (settings_.axes > 1 && scan_running()) {
          return refuse("a scan is running: an experiment on one axis would tear the path the others follow");
        }
        const bool queued = driven.experiment_running();
        driven.start_experiment(e);
        if (const LogLimiter::Gate g = acted()) {
          spdlog::info("experiment {} {} V + {} V at {} Hz for {} s {} (request {}){}", escape_wire(msg.experiment),
                       e.amplitude_V, e.offset_V, e.frequency_hz, e.duration_s,
                       queued ? "queued, " + std::to_string(driven.experiments_queued()) + " waiting" : "started",
                       msg.request_id, suppressed_note(g));
        }
        break;
      }
      case control_t::STOP_EXPERIMENT: {
        // Whichever axis runs one: an operator's stop ends every excitation of the stage.
        std::size_t queued = 0;
        for_each_law([&](Compensator& c) {
          queued += c.experiments_queued();
          c.stop_experiment();
        });
        if (const LogLimiter::Gate g = acted()) {
          spdlog::info("experiment stopped, {} queued dropped (request {}){}", queued, msg.request_id,
                       suppressed_note(g));
        }
        break;
      }
      case control_t::SET_LEARNING:
        switch (msg.learning) {
          case control_t::LEARNING_OFF: for_each_law([](Compensator& c) { c.set_learning(false); }); break;
          case control_t::LEARNING_ON: for_each_law([](Compensator& c) { c.set_learning(true); }); break;
          case control_t::LEARNING_RESET: for_each_law([](Compensator& c) { c.reset_learning(); }); break;
          default: return refuse("learning " + std::to_string(msg.learning) + " is not off (0), on (1) or reset (2)");
        }
        if (const LogLimiter::Gate g = acted()) {
          spdlog::info("learning {} (request {}){}",
                       msg.learning == control_t::LEARNING_RESET ? "reset" : (msg.learning ? "on" : "off"),
                       msg.request_id, suppressed_note(g));
        }
        break;
      case control_t::RESET_COUNTERS:
        reported_.rebase(collect_counters());
        reported_.rebase("sensor", samples_.counters());
        reported_.rebase("trajectory", trajectories_.counters());
        reported_.rebase("scan", scans_.counters());
        reported_.rebase("params", params_.counters());
        reported_.rebase("control", control_.counters());
        reported_.rebase("command", command_pub_.counters());
        if (const LogLimiter::Gate g = acted()) {
          spdlog::info("RESET_COUNTERS (request {}){}", msg.request_id, suppressed_note(g));
        }
        break;
      case control_t::SHUTDOWN:
        spdlog::info("SHUTDOWN (request {})", msg.request_id);
        request_stop();
        break;
      default:  // the bridge's (ARM, DISARM, SET_GAINS: the servo runs beside the sensor)
        if (msg.target == "compensator") return refuse("not a compensator command (the bridge's)");
        return;
    }
    ++counters_.control_acted;
    acks_.acted(msg.request_id);
    verdict_due_ = true;
  } catch (const std::exception& e) {
    refuse(e.what());
  }
  if (verdict_due_) report(wall_utime(), false, false);
}

void CompensatorService::restart_control_law() {
  for (int a = 0; a < settings_.axes; ++a) {
    std::optional<Compensator>& law = laws_[static_cast<std::size_t>(a)];
    std::string refusal;
    Compensator next = law->restarted(settings_.control, refusal);
    if (!refusal.empty()) {
      ++counters_.trajectory_refused;
      spdlog::warn("after the bridge's restart the trajectory in force on {} was not taken again: {}", axis_name(a),
                   escape_wire(refusal));
    }
    retired_ += law->counters();
    law.emplace(std::move(next));
  }
  have_sample_ = false;
  ++counters_.bridge_restarts;
}

CounterSet::Entries CompensatorService::collect_counters() const {
  CompensatorCounters c = retired_;
  for (int a = 0; a < settings_.axes; ++a) c += laws_[static_cast<std::size_t>(a)]->counters();
  const CompensatorServiceCounters& s = counters_;
  CounterSet::Entries entries = {{"samples", c.samples},
                                 {"command_blocks_published", s.command_blocks_published},
                                 {"command_ticks_published", s.command_ticks_published},
                                 {"sensor_blocks_wrong_axes", s.sensor_blocks_wrong_axes},
                                 {"planned", c.planned},
                                 {"ticks_behind", c.ticks_behind},
                                 {"gaps", c.gaps},
                                 {"out_of_order", c.out_of_order},
                                 {"nonfinite_outputs", c.nonfinite_outputs},
                                 {"reversals", c.reversals},
                                 {"params_accepted", c.params_accepted},
                                 {"params_rejected", c.params_rejected + s.params_refused},
                                 {"params_invalid", s.params_invalid},
                                 {"params_stale", s.params_stale},
                                 {"params_stale_repeat", s.params_stale_repeat},
                                 {"params_stale_below", s.params_stale_below},
                                 {"params_swapped", c.params_swapped},
                                 {"model_switches", c.model_switches},
                                 {"model_unknown_kind", s.model_unknown_kind},
                                 {"model_unknown_format", s.model_unknown_format},
                                 {"reanchors", c.reanchors},
                                 {"reanchors_skipped", c.reanchors_skipped},
                                 {"u_clamped", c.u_clamped},
                                 {"u_slew_clamped", c.u_slew_clamped},
                                 {"learning_held", c.learning_held},
                                 {"trajectories_shaped", c.trajectories_shaped},
                                 {"stage_swaps", c.stage_swaps},
                                 {"experiment_ramped", c.experiment_ramped},
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
                                 {"log_lines_suppressed", log_limiter_.suppressed_total()}};
  // Scans and what named an axis this stage lacks (a one-axis stage counts them too); with several
  // axes the counters above are summed over the axes' laws (samples: every axis's), and these say
  // how the axes planned together.
  entries.emplace_back("scans", s.scans);
  entries.emplace_back("scans_refused", s.scans_refused);
  entries.emplace_back("wrong_axis", s.wrong_axis);
  if (settings_.axes > 1) {
    entries.emplace_back("axes", static_cast<std::uint64_t>(settings_.axes));
    entries.emplace_back("plan_mismatch", s.plan_mismatch);
  }
  return entries;
}

// Off the sensor path: what the SequenceGuard decided since the last report.
void CompensatorService::log_sequence_events() {
  const SequenceGuard::Counters& g = guard_.counters();
  constexpr int kHeld = SequenceGuard::kConfirmBlocks - 1;
  if (g.restarts != restarts_logged_) {
    const Discontinuity& d = discontinuities_.last_restart();
    spdlog::warn(
        "bridge restart: sensor ticks went back: tick {} was expected, the stream continues from tick {} "
        "(confirmed by {} blocks, the first {} of them held): control law restarted ({} restarts in all)",
        d.expected_tick, d.resumed_tick, SequenceGuard::kConfirmBlocks, kHeld, g.restarts);
  }
  if (g.jumps != jumps_logged_) {
    const Discontinuity& d = discontinuities_.last_jump();
    spdlog::warn(
        "sensor ticks jumped ahead: tick {} was expected, the stream continues from tick {} (confirmed by {} "
        "blocks, the first {} of them held; {} jumps in all)",
        d.expected_tick, d.resumed_tick, SequenceGuard::kConfirmBlocks, kHeld, g.jumps);
  }
  if (g.ignored != ignored_logged_) {
    spdlog::warn(
        "{} jump(s) or restart(s) of the sensor ticks not believed since the last report: not confirmed "
        "by the blocks that followed (a forged or corrupted block?); sensor_jumps_ignored {}, "
        "sensor_blocks_held {} in all",
        g.ignored - ignored_logged_, g.ignored, g.held);
  }
  restarts_logged_ = g.restarts;
  jumps_logged_ = g.jumps;
  ignored_logged_ = g.ignored;
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
  const MemParams& m = c.mem_params();
  detail += fmt::format("mode {}, params v{} c1={:.6g} c2={:.6g} c3={:.6g}, planning {} ticks ahead{}",
                        to_string(c.experiment_running() ? FeedforwardMode::kExperiment : c.mode()), c.params_version(),
                        m.c1, m.c2, m.c3, c.config().horizon_ticks,
                        experimenting < 0    ? std::string()
                        : settings_.axes > 1 ? fmt::format(", experiment running on {}", axis_name(experimenting))
                                             : std::string(", experiment running"));
  if (c.stage().has_dynamics()) {
    detail += fmt::format("; stage {:.4g} Hz zeta {:.3g} inverted",
                          c.stage().second_order.natural_frequency() / (2.0 * std::numbers::pi),
                          c.stage().second_order.damping_ratio());
  }
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

int CompensatorService::run() {
  for (const std::string& line : describe(settings_)) spdlog::info("{}", line);
  spdlog::info("channels: {} in, {} out; {}, {}, {}, {}, {} in", samples_.channel(), command_pub_.channel(),
               trajectories_.channel(), scans_.channel(), params_.channel(), models_.channel(), control_.channel());
  const double started_s = monotonic_s();
  IoLoopOptions options;
  options.poll_timeout = std::chrono::microseconds(20000);
  const int errors = run_io_loop(lcm_, options, [&](std::int64_t utime) {
    report(utime, false);
    if (settings_.run_seconds > 0 && monotonic_s() - started_s >= settings_.run_seconds) {
      spdlog::info("--seconds {} reached", settings_.run_seconds);
      request_stop();
    }
  });
  spdlog::info("stopping{}", stop_signal() ? fmt::format(" on signal {}", stop_signal()) : std::string());
  report(wall_utime(), true);
  // From the counters HX_STATUS carries (collect_counters(): the whole run, across bridge restarts).
  const CounterSet::Entries totals = collect_counters();
  const auto total = [&totals](std::string_view name) {
    const auto it = std::find_if(totals.begin(), totals.end(), [name](const auto& e) { return e.first == name; });
    return it == totals.end() ? std::uint64_t{0} : it->second;
  };
  spdlog::info(
      "summary: {} samples, {} command ticks published in {} blocks, {} ticks planned too late, {} gaps, "
      "{} out of order, params {} accepted / {} refused / {} swapped, {} invalid sets ignored",
      total("samples"), total("command_ticks_published"), total("command_blocks_published"), total("ticks_behind"),
      total("gaps"), total("out_of_order"), total("params_accepted"), total("params_rejected"), total("params_swapped"),
      total("params_invalid"));
  if (latency_total_.count() > 0) {
    spdlog::info("summary: sensor block received -> its answer published p50 {:.1f} us, p99 {:.1f} us, max {:.1f} us",
                 latency_total_.percentile(0.5) / 1e3, latency_total_.percentile(0.99) / 1e3,
                 static_cast<double>(latency_total_.max_ns()) / 1e3);
  }
  write_summary_json();
  return errors > 0 ? 1 : 0;
}

}  // namespace hystloop
