#include "bridge/bridge_realtime.hpp"

#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <ctime>
#include <system_error>

#include "core/periodic_timer.hpp"

namespace hystloop {
namespace {

std::int64_t wall_utime_now() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);  // vDSO: no system call
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000 + ts.tv_nsec / 1000;
}

}  // namespace

BridgeRealtime::BridgeRealtime(const BridgeSettings& settings, std::unique_ptr<StageBackend> backend)
    : settings_(settings),
      backend_(std::move(backend)),
      core_(settings.limits, settings.dt_s()),
      dt_s_(settings.dt_s()),
      auto_arm_pending_(settings.auto_arm) {
  wake_fd_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (wake_fd_ < 0) throw std::system_error(errno, std::generic_category(), "eventfd");
}

BridgeRealtime::~BridgeRealtime() {
  stop();
  if (wake_fd_ >= 0) ::close(wake_fd_);
}

void BridgeRealtime::start() {
  thread_ = std::thread([this] { run(); });
}

void BridgeRealtime::stop() {
  stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

void BridgeRealtime::run() noexcept {
  // Set-up (may log through spdlog when refused; the loop below never does).
  if (settings_.rt.cpu >= 0) {
    try {
      affinity_status_ = set_cpu_affinity({settings_.rt.cpu});
    } catch (const std::exception& e) {
      affinity_status_ = {false, e.what()};
    }
  } else {
    affinity_status_ = {true, "not pinned"};
  }
  if (settings_.rt.priority > 0) {
    priority_status_ = set_realtime_priority(settings_.rt.priority);
  } else {
    priority_status_ = {true, "normal scheduling"};
  }
  PeriodicTimer timer(period_ns_from_rate_hz(settings_.rate_hz));
  started_.store(true, std::memory_order_release);

  while (!stop_.load(std::memory_order_acquire)) {  // the I/O thread stops us after a last report
    const TickInfo info = timer.wait_next();
    tick(static_cast<std::int64_t>(info.tick), info.skipped, info.lateness_ns);
  }
}

void BridgeRealtime::tick(std::int64_t k, std::uint64_t skipped, std::int64_t lateness_ns) noexcept {
  const std::int64_t start_ns = monotonic_now_ns();
  const double t_s = static_cast<double>(k) * dt_s_;
  ticks_skipped_ += skipped;

  switch (arm_request_.exchange(ArmRequest::kNone, std::memory_order_acq_rel)) {
    case ArmRequest::kArm:
      core_.arm(t_s);
      tripped_ = false;
      break;
    case ArmRequest::kDisarm:
      core_.disarm();
      auto_arm_pending_ = false;  // an explicit disarm ends the convenience
      tripped_ = false;           // ... and an operator's disarm is never undone automatically
      break;
    case ArmRequest::kNone: break;
  }
  while (const auto command = commands_.try_pop()) {
    ++commands_processed_;
    if (auto_arm_pending_ && !core_.armed()) {
      core_.arm(t_s);
      auto_arm_pending_ = false;
      ++auto_arms_;
    }
    // Opt-in (actuator.rearm_after_trip_s > 0): after a watchdog trip, re-arm once commands
    // flow again and the safe state has lasted that long. For demos and soak runs on shared
    // machines; counted, and off by default.
    if (tripped_ && !core_.armed() && settings_.rearm_after_trip_s > 0.0 &&
        static_cast<double>(k - last_trip_tick_) * dt_s_ >= settings_.rearm_after_trip_s) {
      core_.arm(t_s);
      tripped_ = false;
      ++auto_arms_;
    }
    core_.submit(command->seq, command->u_V, command->params_version, t_s);
  }
  if (core_.armed()) auto_arm_pending_ = false;  // armed by HX_CONTROL: no auto-arm later

  const BridgeTick decided = core_.tick(k, t_s);
  if (core_.counters().watchdog_trips != trips_seen_) {
    trips_seen_ = core_.counters().watchdog_trips;
    last_trip_tick_ = k;
    tripped_ = true;
  }
  // After an overrun the stage has been holding the last voltage for the skipped ticks too.
  const double step_s = dt_s_ * static_cast<double>(1 + skipped);
  const StageReading reading = backend_->step(decided.u_applied_V, t_s, step_s);
  last_tick_ = k;

  const OutgoingSample sample{k, wall_utime_now(), decided.u_applied_V, reading.y_m, decided.flags | reading.flags};
  if (samples_.try_push(sample)) {
    const std::uint64_t one = 1;
    [[maybe_unused]] const ssize_t n = ::write(wake_fd_, &one, sizeof one);
  } else {
    ++samples_dropped_;
  }

  RtReport& report = reports_.current();
  report.lateness.add(lateness_ns);
  report.work.add(monotonic_now_ns() - start_ns);
  reports_.serve_request([&](RtReport& r) {
    r.core = core_.counters();
    r.ticks_skipped = ticks_skipped_;
    r.samples_dropped = samples_dropped_;
    r.commands_processed = commands_processed_;
    r.auto_arms = auto_arms_;
    r.last_tick = last_tick_;
    r.last_trip_tick = last_trip_tick_;
    r.u_applied_V = core_.last_applied_V();
    r.gain_scale = backend_->gain_scale();
    r.armed = core_.armed();
  });
}

}  // namespace hystloop
