#include "bridge/bridge_realtime.hpp"

#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <ctime>
#include <chrono>
#include <system_error>
#include <thread>

#include <spdlog/spdlog.h>

#include "core/errors.hpp"
#include "core/clock.hpp"  // wall_utime: clock_gettime through the vDSO, no system call
#include "core/periodic_timer.hpp"

namespace hystloop {

namespace {
int axes_checked(const BridgeSettings& settings, const StageBackend& backend) {
  if (backend.axes() != settings.axes) {
    throw ParameterError("bridge.axes", "is " + std::to_string(settings.axes) + " but the backend " + backend.name() +
                                            " drives " + std::to_string(backend.axes()));
  }
  return settings.axes;
}
}  // namespace

BridgeRealtime::BridgeRealtime(const BridgeSettings& settings, std::unique_ptr<StageBackend> backend)
    : settings_(settings),
      backend_(std::move(backend)),
      stage_(axes_checked(settings, *backend_),
             std::span<const ActuatorLimits>(settings.axes_limits()).first(static_cast<std::size_t>(settings.axes)),
             std::span<const FeedbackGains>(settings.axes_servo()).first(static_cast<std::size_t>(settings.axes)),
             settings.dt_s()),
      arming_(ArmingSettings{settings.auto_arm, settings.rearm_after_trip_s, settings.dt_s()}),
      dt_s_(settings.dt_s()),
      safe_u_V_(settings.safe_voltages()) {
  stage_.set_max_lead_ticks(std::llround(settings.max_lead_s * settings.rate_hz));
  max_stall_ticks_ = std::llround(settings.max_stall_s * settings.rate_hz);
  for (int a = 0; a < settings.axes; ++a) {
    position_min_m_[static_cast<std::size_t>(a)] = settings.limits_of(a).position_min_m;
    position_max_m_[static_cast<std::size_t>(a)] = settings.limits_of(a).position_max_m;
    oscillation_[static_cast<std::size_t>(a)] = OscillationDetector(settings.oscillation, settings.rate_hz);
  }
  wake_fd_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (wake_fd_ < 0) throw std::system_error(errno, std::generic_category(), "eventfd");
}

BridgeRealtime::~BridgeRealtime() {
  // The service stops us after the ramp; still running here means it did not get there (an
  // exception unwinding): the ramp happens now, before the thread ends.
  const bool running = thread_.joinable();
  const SafeStopResult r = stop();
  if (running) {
    if (r.reached) {
      spdlog::warn("stopped without the service's stop: ramped x from {:.6g} V to the safe {} V in {} ticks ({:.4g} s)",
                   r.u_start_V, settings_.limits.safe_u_V, r.ramp_ticks, r.ramp_s);
    } else {
      spdlog::error("stopped without the service's stop: the ramp to the safe voltage did not end within {} s",
                    settings_.stop_ramp_timeout_s);
    }
  }
  if (wake_fd_ >= 0) ::close(wake_fd_);
}

bool BridgeRealtime::push_commands(std::span<const CommandTick> per_axis) noexcept {
  if (per_axis.size() != static_cast<std::size_t>(stage_.axes())) return false;
  TickCommands t;
  for (std::size_t a = 0; a < per_axis.size(); ++a) t.axis[a] = per_axis[a];
  return commands_.try_push(t);
}

void BridgeRealtime::start() {
  thread_ = std::thread([this] { run(); });
}

void BridgeRealtime::begin_safe_stop() noexcept {
  if (stop_result_.requested) return;
  stop_result_.requested = true;
  safe_stop_begin_ns_ = monotonic_ns();
  safe_stop_.store(true, std::memory_order_release);
}

SafeStopResult BridgeRealtime::stop() {
  if (thread_.joinable()) {
    begin_safe_stop();
    const std::int64_t deadline_ns =
        safe_stop_begin_ns_ + static_cast<std::int64_t>(settings_.stop_ramp_timeout_s * 1e9);
    while (!safe_reached() && monotonic_ns() < deadline_ns) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const std::int64_t waited_ns = monotonic_ns() - safe_stop_begin_ns_;
    stop_.store(true, std::memory_order_release);
    thread_.join();
    // Joined: the thread's stop_* fields are ours to read.
    stop_result_.reached = safe_reached();
    stop_result_.u_start_V = stop_u_start_V_;
    stop_result_.ramp_ticks = stop_ramp_ticks_;
    stop_result_.ramp_s = static_cast<double>(stop_ramp_ticks_) * dt_s_;
    stop_result_.wall_s =
        static_cast<double>(stop_result_.reached ? stop_reached_ns_ - safe_stop_begin_ns_ : waited_ns) * 1e-9;
  }
  backend_->hold_safe(safe_voltages());  // after the ramp, and whatever happened before
  return stop_result_;
}

void BridgeRealtime::run() noexcept {
  // Set-up (may log through spdlog when refused; the loop below never does).
  affinity_status_ = {true, "not pinned"};
  try {
    if (settings_.rt.cpu >= 0) affinity_status_ = set_cpu_affinity({settings_.rt.cpu});
  } catch (const std::exception& e) {
    affinity_status_ = {false, e.what()};
  }
  priority_status_ =
      settings_.rt.priority > 0 ? set_realtime_priority(settings_.rt.priority) : SetupStatus{true, "normal scheduling"};
  const std::int64_t per_wake = settings_.rt.ticks_per_wake;
  PeriodicTimer timer(period_ns_from_rate_hz(settings_.rate_hz) * per_wake);
  started_.store(true, std::memory_order_release);

  // A simulated stage has no wall clock: ticks whose deadline passed are run late (counted), so
  // its samples never have gaps; but at most twice a wake-up's ticks per wake-up, so that after a
  // long stall the simulated clock catches up over a few milliseconds while the compensator keeps
  // refilling the buffer — one burst of a stall's ticks would run the buffer dry at once and trip
  // the watchdog (seen on a fresh clone while another build ran: a 50 ms stall, 480 stale
  // commands). Hardware cannot go back in time: missed deadlines are skipped.
  const bool catch_up = backend_->simulated();
  std::int64_t next = 0;                            // the next tick to run
  while (!stop_.load(std::memory_order_acquire)) {  // the I/O thread stops us after a last report
    const TickInfo info = timer.wait_next();
    const std::int64_t due = (static_cast<std::int64_t>(info.tick) + 1) * per_wake;  // ticks [0, due) are due
    std::uint64_t skipped = 0;
    if (!catch_up && next < due - per_wake) {
      skipped = static_cast<std::uint64_t>(due - per_wake - next);
      ticks_skipped_ += skipped;
      next = due - per_wake;
      note_skipped(next, skipped);
    }
    const std::int64_t end = catch_up ? std::min(due, next + 2 * per_wake) : due;
    if (end - next > per_wake) ticks_caught_up_ += static_cast<std::uint64_t>(end - next - per_wake);
    std::int64_t start_ns = info.wake_ns;  // the work of a wake-up's first tick counts from the wake-up
    for (std::int64_t k = next; k < end; ++k) start_ns = tick(k, k == next ? skipped : 0, start_ns);
    next = end;
    RtReport& report = reports_.current();
    report.lateness.add(info.lateness_ns);
  }
}

void BridgeRealtime::note_skipped(std::int64_t k, std::uint64_t skipped) noexcept {
  const auto window_ticks = static_cast<std::int64_t>(std::llround(settings_.rate_hz));
  if (k - stall_window_start_ >= window_ticks) {
    stall_window_start_ = k;
    skipped_in_window_ = 0;
  }
  skipped_in_window_ += skipped;
  if (static_cast<std::int64_t>(skipped_in_window_) <= max_stall_ticks_ || !stage_.armed()) return;
  // The outputs held stale voltages for longer than the rig allows: every axis ramps to its safe
  // voltage from this tick (BridgeCore's safe state), until re-armed.
  arming_.request(ArmRequest::kDisarm, k, stage_);
  ++stall_trips_;
  last_stall_tick_ = k;
  last_stall_ticks_ = skipped_in_window_;
  stall_window_start_ = k;
  skipped_in_window_ = 0;
}

void BridgeRealtime::check_positions(std::int64_t k, std::span<const StageReading> readings) noexcept {
  for (std::size_t a = 0; a < readings.size(); ++a) {
    const double y = readings[a].y_m;  // NaN (a failed read) is no excursion: the backend counts it
    if (!(y < position_min_m_[a] || y > position_max_m_[a])) {
      beyond_ticks_[a] = 0;
      continue;
    }
    if (++beyond_ticks_[a] < ActuatorLimits::kPositionLimitTicks || !stage_.armed()) continue;
    arming_.request(ArmRequest::kDisarm, k, stage_);  // every axis ramps to safe from the next tick
    ++position_trips_;
    position_axis_ = static_cast<int>(a);
    position_m_ = y;
    position_tick_ = k;
    beyond_ticks_[a] = 0;
  }
}

void BridgeRealtime::check_oscillation(std::int64_t k, std::span<const BridgeTick> decided) noexcept {
  if (!stage_.armed()) {  // disarmed, the servo is off: a re-armed loop is watched afresh
    for (std::size_t a = 0; a < decided.size(); ++a) oscillation_[a].reset();
    return;
  }
  for (std::size_t a = 0; a < decided.size(); ++a) {
    if (!oscillation_[a].observe(decided[a].u_fb_V)) continue;
    arming_.request(ArmRequest::kDisarm, k, stage_);  // every axis ramps to safe from the next tick
    ++oscillation_trips_;
    oscillation_axis_ = static_cast<int>(a);
    oscillation_hz_ = oscillation_[a].frequency_hz();
    oscillation_rms_V_ = oscillation_[a].tripped_rms_V();
    oscillation_tick_ = k;
  }
}

std::int64_t BridgeRealtime::tick(std::int64_t k, std::uint64_t skipped, std::int64_t start_ns) noexcept {
  const auto axes = static_cast<std::size_t>(stage_.axes());
  if (!arming_.stopping() && safe_stop_.load(std::memory_order_acquire)) {
    stop_u_start_V_ = stage_.axis(0).last_applied_V();
    arming_.stop(stage_);  // from this tick every axis ramps to the safe voltage and is never armed again
  }
  arming_.request(arm_request_.exchange(ArmRequest::kNone, std::memory_order_acq_rel), k, stage_);
  while (const auto change = gains_.try_pop()) {
    for (std::size_t a = 0; a < axes; ++a) {
      if (change->set[a]) stage_.set_servo_gains(static_cast<int>(a), change->gains[a]);
    }
  }
  while (const auto commands = commands_.try_pop()) {
    ++commands_processed_;
    commands_seen_ = true;
    for (std::size_t a = 0; a < axes; ++a) stage_.submit(static_cast<int>(a), commands->axis[a]);
  }
  arming_.before_tick(k, commands_seen_, stage_);

  std::array<double, kMaxAxes> u_before_V{};
  for (std::size_t a = 0; a < axes; ++a) u_before_V[a] = stage_.axis(static_cast<int>(a)).last_applied_V();
  std::array<BridgeTick, kMaxAxes> decided{};
  stage_.tick(k, std::span(y_last_m_).first(axes), decided);
  arming_.after_tick(k, stage_);
  check_oscillation(k, std::span<const BridgeTick>(decided).first(axes));
  if (const std::uint64_t trips = stage_.counters().watchdog_trips; trips != trips_seen_) {
    trips_seen_ = trips;
    last_trip_ns_ = start_ns;
  }
  std::int64_t depth = decided[0].buffer_depth;
  for (std::size_t a = 1; a < axes; ++a) depth = std::min(depth, decided[a].buffer_depth);
  if (stage_.armed() && commands_seen_) {
    min_depth_period_ = min_depth_period_ < 0 ? depth : std::min(min_depth_period_, depth);
    min_depth_total_ = min_depth_total_ < 0 ? depth : std::min(min_depth_total_, depth);
  }
  // After an overrun the stage has been holding the last voltage for the skipped ticks too.
  const double step_s = dt_s_ * static_cast<double>(1 + skipped);
  const double t_s = static_cast<double>(k) * dt_s_;
  std::array<double, kMaxAxes> u_V{};
  for (std::size_t a = 0; a < axes; ++a) u_V[a] = decided[a].u_applied_V;
  // The amplifier enable: active while armed or on the way to the safe voltages, not once there.
  bool enabled = stage_.armed();
  for (std::size_t a = 0; a < axes; ++a) enabled = enabled || u_V[a] != safe_u_V_[a];
  backend_->set_output_enabled(enabled);
  std::array<StageReading, kMaxAxes> readings{};
  backend_->step_axes(std::span(u_V).first(axes), t_s, step_s, std::span(readings).first(axes));
  bool go_safe = false;
  for (std::size_t a = 0; a < axes; ++a) {
    go_safe = go_safe || readings[a].go_safe;
    y_last_m_[a] = readings[a].y_m;
  }
  if (go_safe && stage_.armed()) arming_.request(ArmRequest::kDisarm, k, stage_);  // from the next tick
  check_positions(k, std::span<const StageReading>(readings).first(axes));
  last_tick_ = k;
  bool reached_now = false;
  if (arming_.stopping() && !safe_reached_.load(std::memory_order_relaxed)) {
    bool moved = false;
    bool at_safe = !stage_.armed();
    for (std::size_t a = 0; a < axes; ++a) {
      moved = moved || decided[a].u_applied_V != u_before_V[a];
      at_safe = at_safe && decided[a].u_applied_V == safe_u_V_[a];
    }
    if (moved) ++stop_ramp_ticks_;
    if (at_safe) {
      stop_reached_ns_ = monotonic_ns();
      backend_->hold_safe(safe_voltages());
      reached_now = true;  // published once this tick's sample is queued
    }
  }

  OutgoingTick out;
  const std::int64_t utime = wall_utime();
  for (std::size_t a = 0; a < axes; ++a) {
    const BridgeTick& d = decided[a];
    out.ticks[a] = SensorTick{utime,    k,         d.u_applied_V,   d.u_ff_V,
                              d.u_fb_V, d.y_ref_m, readings[a].y_m, d.flags | readings[a].flags};
    out.y_true_m[a] = readings[a].y_true_m;
  }
  out.buffer_depth = static_cast<std::int32_t>(std::min<std::int64_t>(depth, INT32_MAX));
  out.axes = static_cast<std::int32_t>(axes);
  if (samples_.try_push(out)) {
    if ((k + 1) % settings_.block_ticks == 0) {  // a block is complete: wake the I/O thread
      const std::uint64_t one = 1;
      [[maybe_unused]] const ssize_t n = ::write(wake_fd_, &one, sizeof one);
    }
  } else {
    ++samples_dropped_;
  }
  if (reached_now) safe_reached_.store(true, std::memory_order_release);

  RtReport& report = reports_.current();
  const std::int64_t end_ns = monotonic_ns();
  report.work.add(end_ns - start_ns);
  reports_.serve_request([&](RtReport& r) {
    r.core = stage_.counters();
    r.axes = static_cast<int>(axes);
    r.tripped_by = stage_.tripped_by();
    for (std::size_t a = 0; a < axes; ++a) {
      r.axis_core[a] = stage_.axis(static_cast<int>(a)).counters();
      r.axis_u_V[a] = stage_.axis(static_cast<int>(a)).last_applied_V();
    }
    r.ticks_skipped = ticks_skipped_;
    r.stall_trips = stall_trips_;
    r.last_stall_tick = last_stall_tick_;
    r.last_stall_ticks = last_stall_ticks_;
    r.position_trips = position_trips_;
    r.position_axis = position_axis_;
    r.position_m = position_m_;
    r.position_tick = position_tick_;
    r.oscillation_trips = oscillation_trips_;
    r.oscillation_axis = oscillation_axis_;
    r.oscillation_hz = oscillation_hz_;
    r.oscillation_rms_V = oscillation_rms_V_;
    r.oscillation_tick = oscillation_tick_;
    r.ticks_caught_up = ticks_caught_up_;
    r.samples_dropped = samples_dropped_;
    r.commands_processed = commands_processed_;
    r.last_tick = last_tick_;
    r.last_trip_tick = arming_.last_trip_tick();
    r.last_trip_ns = last_trip_ns_;
    r.min_depth_period = min_depth_period_;
    r.min_depth_total = min_depth_total_;
    r.buffer_depth = stage_.buffer_depth();
    r.clamped_last_second = stage_.clamped_last_second();
    r.u_applied_V = stage_.axis(0).last_applied_V();
    r.gain_scale = backend_->gain_scale();
    r.armed = stage_.armed();
    min_depth_period_ = -1;
  });
  return end_ns;  // a status period's hand-over above counts in the next tick's work (once a second)
}

}  // namespace hystloop
