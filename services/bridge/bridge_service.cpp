#include "bridge/bridge_service.hpp"

#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <chrono>
#include <ctime>
#include <exception>
#include <thread>

#include <spdlog/spdlog.h>

#include "bridge/bridge_health.hpp"
#include "bridge/servo_request.hpp"
#include "core/clock.hpp"
#include "core/process.hpp"
#include "lcm/blocks.hpp"
#include "lcm/connection.hpp"
#include "lcm/message_checks.hpp"
#include "lcm/actuator_status.hpp"
#include "lcm/servo_gains_status.hpp"
#include "runtime/rig_auth_config.hpp"
#include "runtime/summary_file.hpp"

namespace hystloop {

BridgeService::BridgeService(const BridgeSettings& settings, lcm::LCM& lcm, const ChannelNames& channels)
    : settings_(settings),
      lcm_(lcm),
      rt_(settings, make_stage_backend(settings)),
      sensor_pub_(lcm, channels.sensor),
      commands_(lcm, channels.command, [this](const command_block_t& msg, std::int64_t) { on_command(msg); },
                {.queue_capacity = settings.command_queue_capacity, .on_reject = {}}),
      control_(lcm, channels.control, [this](const control_t& msg, std::int64_t) { on_control(msg); }),
      status_(lcm, channels.status, "bridge"),
      gains_(settings.axes_servo()) {
  reserve_storage(block_);
  begin_block(block_, 0, 0, settings_.dt_s(), settings_.axes);
  if (rt_.backend().simulated()) {
    truth_pub_.emplace(lcm, channels.sim_truth);
    reserve_storage(truth_);
  }
}

void BridgeService::on_command(const command_block_t& msg) noexcept {
  ++command_blocks_;
  if (msg.n_axes != settings_.axes) {  // planned for another stage: no axis of it is guessed at
    ++command_blocks_wrong_axes_;
    return;
  }
  if (const auto elapsed = sent_.elapsed_since(msg.sample_seq, monotonic_ns())) {
    latency_.add(*elapsed);
    latency_total_.add(*elapsed);
  }
  last_command_ns_ = monotonic_ns();
  std::array<CommandTick, kMaxAxes> tick{};
  const auto axes = static_cast<std::size_t>(settings_.axes);
  for (std::size_t i = 0, n = ticks_of(msg); i < n; ++i) {
    for (std::size_t a = 0; a < axes; ++a) tick[a] = command_tick(msg, i, a);
    if (!rt_.push_commands(std::span<const CommandTick>(tick).first(axes))) ++command_queue_full_;
  }
}

void BridgeService::act(const control_t& msg, const char* what) {
  ++control_acted_;
  acks_.acted(msg.request_id);
  if (what != nullptr) spdlog::info("{} (request {})", what, msg.request_id);
}

void BridgeService::refuse(const control_t& msg, const std::string& what, std::string why) {
  ++control_refused_;
  spdlog::warn("{} (request {}) refused: {}", what, msg.request_id, why);
  acks_.refused(msg.request_id, std::move(why), wall_utime());
}

void BridgeService::on_control(const control_t& msg) {
  if (!filter_.accept(msg)) return;
  switch (msg.command) {
    case control_t::ARM:
      // The real-time thread would not arm either.
      if (stopping_) return refuse(msg, "ARM", "the bridge is stopping (ramping to the safe voltage)");
      act(msg, "ARM");
      rt_.request_arm(ArmRequest::kArm);
      return;
    case control_t::DISARM:
      act(msg, "DISARM");
      rt_.request_arm(ArmRequest::kDisarm);
      safe_reason_ = "disarmed via HX_CONTROL";
      return;
    case control_t::SET_GAINS: {
      AxisGainsChange change;
      try {
        change = requested_axis_gains(gains_, settings_.axes, msg);
      } catch (const std::exception& e) {
        return refuse(msg, "SET_GAINS", e.what());  // the gains in force stay, on every axis
      }
      if (!rt_.push_gains(change)) {
        return refuse(msg, "SET_GAINS", "the real-time thread has not taken the last gains yet: send again");
      }
      act(msg, nullptr);
      gains_ = change.gains;
      for (int a = 0; a < settings_.axes; ++a) {
        if (!change.set[static_cast<std::size_t>(a)]) continue;
        const FeedbackGains& g = gains_[static_cast<std::size_t>(a)];
        spdlog::info("servo{} gains kp {}, ki {} 1/s, kd {} s, {} (request {})",
                     settings_.axes > 1 ? fmt::format(" {}", axis_name(a)) : std::string(), g.kp, g.ki, g.kd,
                     notches_text(g), msg.request_id);
      }
      return;
    }
    case control_t::RESET_COUNTERS:
      act(msg, "RESET_COUNTERS");
      // All counters from the next report on (asked for at once, so at most a tick of the
      // real-time thread's events is not counted).
      counters_.rebase("command", commands_.counters());
      counters_.rebase("control", control_.counters());
      counters_.rebase("sensor", sensor_pub_.counters());
      reset_pending_ = true;
      return;
    case control_t::SHUTDOWN:
      act(msg, "SHUTDOWN");
      request_stop();
      return;
    default:
      // Meant for the compensator; refused only when addressed to the bridge by name.
      if (msg.target == "bridge") {
        refuse(msg, "control command " + std::to_string(msg.command),
               "command " + std::to_string(msg.command) +
                   " is not the bridge's (arm, disarm, gains, reset-counters, shutdown)");
      }
      return;
  }
}

void BridgeService::publish_block() noexcept {
  if (block_.n_ticks == 0) return;
  // Never a silent hole in the record: values the contract refuses (a servo gone wild, a sensor
  // reading NaN) are replaced and flagged, and what still cannot be sent is counted and logged.
  if (const SensorRepair r = repair_.repair(block_); r.any()) {
    ++sensor_blocks_repaired_;
    sensor_ticks_repaired_ += static_cast<std::uint64_t>(r.ticks);
    if (const LogLimiter::Gate g = log_limiter_.allow(kLogSensorRepaired, monotonic_ns())) {
      spdlog::warn(
          "sensor block from seq {}: {} of {} ticks held values the message contract refuses ({} voltages clamped "
          "to +-{} V and flagged SATURATED, {} positions replaced by the last good one and flagged SENSOR_FAULT, {} "
          "references and {} flag words cleared{}); published repaired ({} ticks in {} blocks so far){}",
          block_.seq, r.ticks, block_.n_ticks, r.voltages, kMaxAbsVoltage_V, r.positions, r.references, r.flag_words,
          r.buffer_depth ? ", a negative buffer depth set to 0" : "", sensor_ticks_repaired_, sensor_blocks_repaired_,
          suppressed_note(g));
    }
  }
  if (sensor_pub_.publish(block_)) {
    ++sensor_blocks_;
  } else {
    ++sensor_blocks_unpublished_;
    sensor_ticks_unpublished_ += static_cast<std::uint64_t>(block_.n_ticks);
    if (const LogLimiter::Gate g = log_limiter_.allow(kLogSensorUnpublished, monotonic_ns())) {
      spdlog::error(
          "sensor block from seq {} ({} ticks) could not be published: {} ticks missing from the record "
          "so far (sensor_ticks_unpublished){}",
          block_.seq, block_.n_ticks, sensor_ticks_unpublished_, suppressed_note(g));
    }
  }
  sent_.record(last_seq(block_), monotonic_ns());
  publish_truth();
  begin_block(block_, 0, 0, settings_.dt_s(), settings_.axes);
}

void BridgeService::publish_truth() noexcept {
  // The truth's ticks are the sensor block's: same seq, same count. A tick without a finite truth
  // leaves the block short, and a short block is not sent, so a receiver never pairs it wrongly.
  if (truth_pub_ && truth_.n_ticks > 0 && truth_.n_ticks == block_.n_ticks && !truth_pub_->publish(truth_)) {
    ++truth_unpublished_;
  }
}

void BridgeService::append_truth(const OutgoingTick& t) noexcept {
  if (!truth_pub_) return;
  // the tick just appended began a block: so does the truth's
  if (block_.n_ticks == 1) begin_block(truth_, block_.seq, block_.utime, settings_.axes);
  const auto axes = static_cast<std::size_t>(t.axes);
  for (std::size_t a = 0; a < axes; ++a) {
    if (!std::isfinite(t.y_true_m[a])) return;
  }
  if (truth_.n_ticks != block_.n_ticks - 1) return;
  append_tick(truth_, std::span(t.y_true_m).first(axes));  // within the reserved MAX_VALUES
}

void BridgeService::publish_samples(bool flush) noexcept {
  while (const auto t = rt_.pop_tick()) {
    // A block holds consecutive ticks and ends at a multiple of block_ticks (or at a gap).
    const SensorTick& tick = t->tick();
    if (block_.n_ticks > 0 && tick.seq != last_seq(block_) + 1) publish_block();
    if (block_.n_ticks == 0) begin_block(block_, tick.seq, tick.utime, settings_.dt_s(), settings_.axes);
    append_tick(block_, std::span(t->ticks).first(static_cast<std::size_t>(t->axes)));
    append_truth(*t);
    block_.buffer_depth_ticks = t->buffer_depth;
    if ((tick.seq + 1) % settings_.block_ticks == 0 || block_.n_ticks == sensor_block_t::MAX_TICKS) publish_block();
  }
  if (flush) publish_block();
}

void BridgeService::serve(bool stopping) {
  using clock = std::chrono::steady_clock;
  // Once a stop is requested its eventfd stays readable: the stopping phase polls without it.
  pollfd fds[3] = {{lcm_.getFileno(), POLLIN, 0}, {rt_.wake_fd(), POLLIN, 0}, {stop_fd(), POLLIN, 0}};
  const nfds_t nfds = stop_fd() >= 0 && !stopping ? 3 : 2;
  const timespec timeout{0, stopping ? 2'000'000 : 20'000'000};  // status, --seconds and the ramp checked this often
  const int ready = ppoll(fds, nfds, &timeout, nullptr);
  const std::int64_t pass_start_ns = monotonic_ns();
  if (last_pass_end_ns_ >= 0) longest_wait_ns_ = std::max(longest_wait_ns_, pass_start_ns - last_pass_end_ns_);
  if (ready < 0 && errno != EINTR) ++lcm_errors_;
  if (fds[1].revents & POLLIN) {
    std::uint64_t count = 0;
    [[maybe_unused]] const ssize_t n = ::read(rt_.wake_fd(), &count, sizeof count);
  }
  publish_samples(false);
  if ((fds[0].revents & POLLIN) && dispatch_pending(lcm_) < 0) ++lcm_errors_;
  const auto now = clock::now();
  // A control request answered is reported at once: its sender waits for the answer.
  if ((now >= next_report_ || reset_pending_ || acks_.due()) && !awaiting_report_) {
    rt_.reports().request();
    awaiting_report_ = true;
    if (now >= next_report_) next_report_ += std::chrono::seconds(1);
  }
  if (awaiting_report_) {
    if (const RtReport* r = rt_.reports().take()) {
      report(*r, wall_utime(), stopping);
      rt_.reports().release();
      awaiting_report_ = false;
    }
  }
  last_pass_end_ns_ = monotonic_ns();
  longest_pass_ns_ = std::max(longest_pass_ns_, last_pass_end_ns_ - pass_start_ns);
}

int BridgeService::run() {
  for (const std::string& line : describe(settings_)) spdlog::info("{}", line);
  spdlog::info("channels: {} out, {} and {} in", sensor_pub_.channel(), commands_.channel(), control_.channel());
  rt_.start();
  while (!rt_.started()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  spdlog::info("real-time thread: {}; {}", rt_.priority_status().detail, rt_.affinity_status().detail);
  // Never armed: the clock thread is stopped again through the safe state, and the bridge exits 1.
  const bool real_time_missing = settings_.rt.required && !rt_.priority_status().ok;
  if (real_time_missing) {
    spdlog::error("{}", real_time_refused(rt_.priority_status().detail));
    request_stop();
  }

  spdlog::info("started in the safe state ({} V); {}", settings_.limits.safe_u_V,
               settings_.auto_arm ? "arms when commands flow" : "waiting for ARM on HX_CONTROL");

  using clock = std::chrono::steady_clock;
  const auto started = clock::now();
  next_report_ = started + std::chrono::seconds(1);
  auto next_network_check = started + std::chrono::seconds(1);
  while (!stop_requested()) {
    serve(false);
    if (clock::now() >= next_network_check) {  // a keyless bridge that finds itself on a network stops, ramped
      next_network_check += std::chrono::seconds(1);
      keyless_network_reached();
    }
    if (settings_.run_seconds > 0 && clock::now() - started >= std::chrono::duration<double>(settings_.run_seconds)) {
      spdlog::info("--seconds {} reached", settings_.run_seconds);
      request_stop();
    }
  }

  // Every stop goes through the safe state first: BridgeCore disarms and ramps to safe_u_V while
  // the real-time thread still runs and its samples are still published, for at most
  // stop_ramp_timeout_s (the longest ramp plus kStopRampMargin_s).
  spdlog::info("stopping{}: ramping to the safe {} V at {} V/s (at most {} s) before the real-time thread ends",
               stop_signal() ? fmt::format(" on signal {}", stop_signal()) : std::string(), settings_.limits.safe_u_V,
               settings_.limits.safe_ramp_rate_V_per_s(), settings_.stop_ramp_timeout_s);
  stopping_ = true;
  rt_.begin_safe_stop();
  const auto deadline = clock::now() + std::chrono::duration<double>(settings_.stop_ramp_timeout_s);
  while (!rt_.safe_reached() && clock::now() < deadline) serve(true);

  // One last report from the real-time thread before it stops.
  if (!awaiting_report_) rt_.reports().request();
  const RtReport* last = nullptr;
  for (int i = 0; i < 100 && last == nullptr; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    last = rt_.reports().take();
  }
  const SafeStopResult safe = rt_.stop();
  publish_samples(true);
  log_safe_stop(safe);
  if (last == nullptr) last = rt_.reports().take();
  if (last != nullptr) {
    report(*last, wall_utime(), true);
    summarize(*last, safe);
  }
  return lcm_errors_ > 0 || !safe.reached || real_time_missing ? 1 : 0;
}

void BridgeService::log_safe_stop(const SafeStopResult& r) const {
  if (r.reached) {
    spdlog::info(
        "safe state reached: ramped from {:.6g} V to the safe {} V in {} ticks ({:.4g} s loop time, {:.4g} s "
        "wall; bound {} s); the real-time thread has ended",
        r.u_start_V, settings_.limits.safe_u_V, r.ramp_ticks, r.ramp_s, r.wall_s, settings_.stop_ramp_timeout_s);
  } else {
    spdlog::error(
        "the ramp to the safe {} V did not end within {} s (the longest ramp + margin; from {:.6g} V, "
        "{} ticks ramped); the backend was told to hold the safe voltage",
        settings_.limits.safe_u_V, settings_.stop_ramp_timeout_s, r.u_start_V, r.ramp_ticks);
  }
}

// The counters HX_STATUS carries, under their names; the summary file writes the same list.
CounterSet::Entries BridgeService::counter_entries(const RtReport& rt) const {
  const BridgeCounters& core = rt.core;
  CounterSet::Entries now = {
      {"ticks", core.ticks},
      {"applied", core.applied},
      {"late", core.late},
      {"stale", core.stale},
      {"duplicates", core.duplicates},
      {"rejected_nonfinite", core.rejected_nonfinite},
      {"rejected_future", core.rejected_future},
      {"clamped", core.clamped},
      {"slew_limited", core.slew_limited},
      {"clamped_either", core.clamped_either},
      {"watchdog_trips", core.watchdog_trips},
      {"safe_ticks", core.safe_ticks},
      {"ticks_skipped", rt.ticks_skipped},
      {"stall_trips", rt.stall_trips},
      {"position_trips", rt.position_trips},
      {"oscillation_trips", rt.oscillation_trips},
      {"ticks_caught_up", rt.ticks_caught_up},
      {"samples_dropped", rt.samples_dropped},
      {"command_queue_full", command_queue_full_},
      {"command_blocks", command_blocks_},
      {"command_blocks_wrong_axes", command_blocks_wrong_axes_},
      {"sensor_blocks", sensor_blocks_},
      {"sensor_blocks_repaired", sensor_blocks_repaired_},
      {"sensor_ticks_repaired", sensor_ticks_repaired_},
      {"sensor_blocks_unpublished", sensor_blocks_unpublished_},
      {"sensor_ticks_unpublished", sensor_ticks_unpublished_},
      {"control_acted", control_acted_},
      {"control_refused", control_refused_},
  };
  if (rt.axes > 1) {  // the sums above, axis by axis: which axis clamps, which is late
    now.emplace_back("axes", static_cast<std::uint64_t>(rt.axes));
    for (int a = 0; a < rt.axes; ++a) {
      const BridgeCounters& c = rt.axis_core[static_cast<std::size_t>(a)];
      const std::string p = std::string(axis_name(a)) + "_";
      now.emplace_back(p + "applied", c.applied);
      now.emplace_back(p + "late", c.late);
      now.emplace_back(p + "stale", c.stale);
      now.emplace_back(p + "rejected_nonfinite", c.rejected_nonfinite);
      now.emplace_back(p + "clamped", c.clamped);
      now.emplace_back(p + "slew_limited", c.slew_limited);
      now.emplace_back(p + "clamped_either", c.clamped_either);
    }
  }
  rt_.backend().append_counters(now);  // e.g. comedi: sensor_faults, sensor_fault_safe, comedi_read_errors
  if (truth_pub_) now.emplace_back("sim_truth_unpublished", truth_unpublished_);
  return now;
}

bool BridgeService::at_safe_voltage(const RtReport& rt) const noexcept {
  if (rt.armed) return false;
  for (int a = 0; a < rt.axes; ++a) {
    if (rt.axis_u_V[static_cast<std::size_t>(a)] != settings_.limits_of(a).safe_u_V) return false;
  }
  return true;
}

void BridgeService::report(const RtReport& rt, std::int64_t utime, bool stopping) {
  const BridgeCounters& core = rt.core;
  CounterSet::Entries now = counter_entries(rt);
  if (reset_pending_) {
    counters_.rebase(now);
    reset_pending_ = false;
  }
  // Late fraction of this report period, over the ticks that were armed.
  const std::uint64_t late = core.late - previous_core_.late;
  const std::uint64_t armed_ticks = late + (core.applied - previous_core_.applied);
  const double late_fraction = armed_ticks > 0 ? static_cast<double>(late) / static_cast<double>(armed_ticks) : 0.0;
  const std::uint64_t dropped = rt.samples_dropped - previous_dropped_;
  const std::uint64_t too_far_ahead = core.rejected_future - previous_core_.rejected_future;
  if (too_far_ahead > 0) {  // once a report period, whatever the state (a disarmed bridge is SAFE)
    spdlog::warn(
        "{} commands refused for ticks more than {} s ahead of the clock (bridge.max_lead_s): a "
        "compensator.horizon_s beyond it, or a sensor stream this bridge did not send",
        too_far_ahead, settings_.max_lead_s);
  }
  previous_core_ = core;
  previous_dropped_ = rt.samples_dropped;
  const std::int64_t now_ns = monotonic_ns();
  const std::uint64_t command_rejected = commands_.counters().rejected_total();
  if (core.watchdog_trips != trips_reported_) {
    trips_reported_ = core.watchdog_trips;
    // With several axes, which one ran dry: all of them went to the safe state on that tick.
    DryBufferFigures dry{.watchdog_s = settings_.limits.watchdog_s,
                         .trip_tick = rt.last_trip_tick,
                         .axes = rt.axes,
                         .tripped_by = rt.tripped_by,
                         .period_s = static_cast<double>(now_ns - last_report_ns_) * 1e-9,
                         .commands_rejected = command_rejected - previous_command_rejected_,
                         .command_queue_full = command_queue_full_ - previous_queue_full_,
                         .io_longest_pass_s = static_cast<double>(longest_pass_ns_) * 1e-9,
                         .io_longest_wait_s = static_cast<double>(longest_wait_ns_) * 1e-9};
    if (last_command_ns_ >= 0 && rt.last_trip_ns >= 0) {
      dry.since_last_command_s = static_cast<double>(rt.last_trip_ns - last_command_ns_) * 1e-9;
      dry.command_after_trip = dry.since_last_command_s < 0.0;
    }
    safe_reason_ = watchdog_reason(dry);
    spdlog::warn("{}", safe_reason_);
  }
  if (rt.stall_trips != stall_trips_reported_) {
    stall_trips_reported_ = rt.stall_trips;
    safe_reason_ = stall_reason(rt.last_stall_ticks, settings_.max_stall_s, settings_.rate_hz, rt.last_stall_tick);
    spdlog::warn("{}", safe_reason_);
  }
  if (rt.position_trips != position_trips_reported_ && rt.position_axis >= 0) {
    position_trips_reported_ = rt.position_trips;
    safe_reason_ = position_reason(rt.position_axis, rt.position_m, settings_.limits_of(rt.position_axis), rt.axes,
                                   rt.position_tick);
    spdlog::warn("{}", safe_reason_);
  }
  if (rt.oscillation_trips != oscillation_trips_reported_ && rt.oscillation_axis >= 0) {
    oscillation_trips_reported_ = rt.oscillation_trips;
    safe_reason_ = oscillation_reason(rt.oscillation_axis, rt.oscillation_hz, rt.oscillation_rms_V,
                                      settings_.oscillation, rt.axes, rt.oscillation_tick);
    spdlog::warn("{}", safe_reason_);
  }
  last_report_ns_ = now_ns;
  previous_command_rejected_ = command_rejected;
  previous_queue_full_ = command_queue_full_;
  longest_pass_ns_ = 0;
  longest_wait_ns_ = 0;

  const BridgeHealthInput health{.stopping = stopping,
                                 .armed = rt.armed,
                                 .at_safe_voltage = at_safe_voltage(rt),
                                 .safe_u_V = settings_.limits.safe_u_V,
                                 .safe_reason = safe_reason_,
                                 .late_fraction = late_fraction,
                                 .degraded_late_fraction = settings_.degraded_late_fraction,
                                 .samples_dropped = dropped,
                                 .samples_repaired = sensor_ticks_repaired_ - previous_repaired_,
                                 .samples_unpublished = sensor_ticks_unpublished_ - previous_unpublished_,
                                 .commands_too_far_ahead = too_far_ahead,
                                 .max_lead_s = settings_.max_lead_s,
                                 .clamped_last_second = rt.clamped_last_second,
                                 .ticks_skipped = rt.ticks_skipped - previous_skipped_,
                                 .dt_s = settings_.dt_s()};
  previous_skipped_ = rt.ticks_skipped;
  previous_repaired_ = sensor_ticks_repaired_;
  previous_unpublished_ = sensor_ticks_unpublished_;
  auto [state, detail] = assess_bridge_health(health);
  if (rt.armed) safe_reason_ = "not armed";  // the next safe state says its own reason
  std::string u;
  if (rt.axes == 1) {
    u = fmt::format("u {:.4g} V", rt.u_applied_V);
  } else {
    for (int a = 0; a < rt.axes; ++a) {
      u += fmt::format("{}{} {:.4g} V", a == 0 ? "u " : ", ", axis_name(a), rt.axis_u_V[static_cast<std::size_t>(a)]);
    }
  }
  detail += fmt::format("{}backend {}{}, {}, gain x{:.4f}, late {:.3g} % this period, buffer {} ticks ahead",
                        detail.empty() ? "" : "; ", rt_.backend().name(),
                        rt.axes > 1 ? fmt::format(" ({} axes)", rt.axes) : std::string(), u, rt.gain_scale,
                        100.0 * late_fraction, rt.buffer_depth);
  if (const std::string note = acks_.refusal_note(utime); !note.empty()) detail += "; " + note;

  status_.begin(state, detail);
  counters_.report(status_, now);
  status_.counter("armed", rt.armed ? 1 : 0);
  acks_.report(status_);
  for (int a = 0; a < settings_.axes; ++a) {
    const FeedbackGains& g = gains_[static_cast<std::size_t>(a)];
    const ServoGainsFigures gains{
        g.kp, g.ki, g.kd, g.notch_hz, g.has_notch() ? g.notch_q : 0.0, g.notch2_hz, g.has_notch2() ? g.notch2_q : 0.0};
    for (const ServoGainCounter& c : kServoGainCounters) {
      status_.counter(servo_gain_counter_name(c, a), servo_gain_counter(c, gains));
    }
    // The rig's actuator limits, which the compensator and the re-identifier hold theirs against.
    const ActuatorLimits& l = settings_.limits_of(a);
    const ActuatorFigures limits{l.u_min_V, l.u_max_V, l.slew_V_per_s};
    for (const ActuatorCounter& c : kActuatorCounters) {
      status_.counter(actuator_counter_name(c, a), actuator_counter(c, limits));
    }
    status_.counter(axis_counter_name(kNominalGainCounter, a), nominal_gain_counter(g.nominal_gain_m_per_V));
  }
  status_.counter("late_ppm_period", static_cast<std::uint64_t>(late_fraction * 1e6));
  status_.counter("clamped_per_s", rt.clamped_last_second.either);
  status_.counter("buffer_depth_ticks", static_cast<std::uint64_t>(std::max<std::int64_t>(0, rt.buffer_depth)));
  if (rt.min_depth_period >= 0) {
    status_.counter("buffer_min_depth_period_ticks", static_cast<std::uint64_t>(rt.min_depth_period));
  }
  if (rt.min_depth_total >= 0)
    status_.counter("buffer_min_depth_ticks", static_cast<std::uint64_t>(rt.min_depth_total));
  if (rt.lateness.count() > 0) {  // the timer's wake-up lateness this period
    status_.counter("timer_lateness_p50_ns", static_cast<std::uint64_t>(rt.lateness.percentile(0.5)));
    status_.counter("timer_lateness_p99_ns", static_cast<std::uint64_t>(rt.lateness.percentile(0.99)));
    status_.counter("timer_lateness_max_ns", static_cast<std::uint64_t>(rt.lateness.max_ns()));
  }
  counters_.report(status_, "command", commands_.counters());
  counters_.report(status_, "control", control_.counters());
  counters_.report(status_, "sensor", sensor_pub_.counters());
  status_.add_rejected(
      static_cast<std::int64_t>(counters_.since("rejected_nonfinite", core.rejected_nonfinite) +
                                counters_.since("rejected_future", core.rejected_future) +
                                counters_.since("command_queue_full", command_queue_full_) +
                                counters_.since("command_blocks_wrong_axes", command_blocks_wrong_axes_) +
                                counters_.since("control_refused", control_refused_)));
  status_.late(static_cast<std::int64_t>(counters_.since("late", core.late)));
  status_.loop_timing(rt.work);
  status_.latency(latency_);
  status_.publish(utime);
  latency_.reset();
}

// The run's figures at exit: the log's summary lines and, with --summary-json, the file.
void BridgeService::summarize(const RtReport& rt, const SafeStopResult& safe) const {
  const BridgeCounters& c = rt.core;
  const double armed_ticks = static_cast<double>(c.applied + c.late);
  const double late_fraction = armed_ticks > 0 ? static_cast<double>(c.late) / armed_ticks : 0.0;
  const CounterSet::Entries entries = counter_entries(rt);
  std::string counts;  // under their HX_STATUS names
  for (const auto& [name, value] : entries) counts += fmt::format(", {} {}", name, value);
  spdlog::info("summary: late {:.3g} % of armed ticks, lowest buffer depth {} ticks, {} command blocks rejected{}",
               100.0 * late_fraction, rt.min_depth_total, commands_.counters().rejected_total(), counts);
  if (latency_total_.count() > 0) {
    spdlog::info(
        "summary: sensor block sent -> its answer received p50 {:.1f} us, p99 {:.1f} us, max {:.1f} us over {} "
        "commands",
        latency_total_.percentile(0.5) / 1e3, latency_total_.percentile(0.99) / 1e3,
        static_cast<double>(latency_total_.max_ns()) / 1e3, latency_total_.count());
  }
  spdlog::info(
      "summary: stop: {} from {:.6g} V to the safe {} V in {} ticks ({:.4g} s loop time, {:.4g} s wall; "
      "bound {} s)",
      safe.reached ? "ramped" : "ramp NOT finished", safe.u_start_V, settings_.limits.safe_u_V, safe.ramp_ticks,
      safe.ramp_s, safe.wall_s, settings_.stop_ramp_timeout_s);
  if (summary_json_path_.empty()) return;

  const double wall_s = monotonic_s() - started_s_;
  const ResourceUsage usage = read_resource_usage();
  const double cpu_s = usage.user_cpu_s + usage.system_cpu_s;
  // Every HX_STATUS counter under its name (counter_entries()), then the figures derived from them.
  nlohmann::ordered_json json;
  for (const auto& [name, value] : entries) json[name] = value;
  json["armed_ticks"] = static_cast<std::uint64_t>(armed_ticks);
  json["late_ticks"] = c.late;
  json["late_tick_fraction"] = late_fraction;
  json["buffer_min_depth_ticks"] = rt.min_depth_total;
  json["rejected"] = c.rejected_nonfinite + c.rejected_future;
  json["block_to_answer_us"] = latency_summary_us(latency_total_);
  json["clamped_ticks"] = {{"range", c.clamped}, {"slew", c.slew_limited}, {"either", c.clamped_either}};
  json["command_blocks_rejected"] = commands_.counters().rejected_total();
  json["wall_s"] = wall_s;
  json["cpu_s"] = cpu_s;
  json["cpu_fraction"] = wall_s > 0 ? cpu_s / wall_s : 0.0;
  json["stop"] = {{"safe_reached", safe.reached},
                  {"u_start_V", safe.u_start_V},
                  {"ramp_ticks", safe.ramp_ticks},
                  {"ramp_s", safe.ramp_s},
                  {"wall_s", safe.wall_s},
                  {"bound_s", settings_.stop_ramp_timeout_s},
                  {"safe_u_V", settings_.limits.safe_u_V}};
  write_summary_file(summary_json_path_, json);
}

}  // namespace hystloop
