#include "bridge/bridge_service.hpp"

#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <ctime>
#include <thread>

#include <spdlog/spdlog.h>

#include "core/periodic_timer.hpp"
#include "core/process.hpp"
#include "runtime/counter_baseline.hpp"

namespace hystloop {
namespace {

BridgeCounters core_since(const BridgeCounters& n, const BridgeCounters& b) noexcept {
  BridgeCounters d;
  d.ticks = n.ticks - b.ticks;
  d.applied = n.applied - b.applied;
  d.late = n.late - b.late;
  d.stale = n.stale - b.stale;
  d.rejected_nonfinite = n.rejected_nonfinite - b.rejected_nonfinite;
  d.rejected_future = n.rejected_future - b.rejected_future;
  d.clamped = n.clamped - b.clamped;
  d.slew_limited = n.slew_limited - b.slew_limited;
  d.watchdog_trips = n.watchdog_trips - b.watchdog_trips;
  d.ignored_disarmed = n.ignored_disarmed - b.ignored_disarmed;
  return d;
}

Subscription<actuator_command_t>::Options command_options(int capacity) {
  Subscription<actuator_command_t>::Options o;
  o.queue_capacity = capacity;
  return o;
}

}  // namespace

BridgeService::BridgeService(const BridgeSettings& settings, lcm::LCM& lcm, const ChannelNames& channels)
    : settings_(settings),
      lcm_(lcm),
      rt_(settings, make_stage_backend(settings.backend, settings.stage)),
      sensor_pub_(lcm, channels.sensor),
      commands_(lcm, channels.command,
                [this](const actuator_command_t& msg, std::int64_t) { on_command(msg); },
                command_options(settings.command_queue_capacity)),
      control_(lcm, channels.control, [this](const control_t& msg, std::int64_t) { on_control(msg); }),
      status_(lcm, channels.status, "bridge") {}

void BridgeService::on_command(const actuator_command_t& msg) noexcept {
  if (const auto elapsed = sent_.elapsed_since(msg.sample_seq, monotonic_now_ns())) {
    latency_.add(*elapsed);
    latency_total_.add(*elapsed);
  }
  if (!rt_.push_command({msg.seq, msg.u_V, msg.params_version})) ++command_queue_full_;
}

void BridgeService::on_control(const control_t& msg) {
  if (!filter_.accept(msg)) return;
  switch (msg.command) {
    case control_t::ARM:
      ++control_acted_;
      rt_.request_arm(ArmRequest::kArm);
      spdlog::info("ARM (request {})", msg.request_id);
      return;
    case control_t::DISARM:
      ++control_acted_;
      rt_.request_arm(ArmRequest::kDisarm);
      safe_reason_ = "disarmed via HX_CONTROL";
      spdlog::info("DISARM (request {})", msg.request_id);
      return;
    case control_t::RESET_COUNTERS:
      ++control_acted_;
      // The I/O thread's counters from now; the real-time thread's from its next report (asked
      // for at once, so at most a tick of its events is not counted).
      baseline_.queue_full = command_queue_full_;
      baseline_.acted = control_acted_;
      baseline_.refused = control_refused_;
      baseline_.commands = commands_.counters();
      baseline_.control = control_.counters();
      baseline_.sensor = sensor_pub_.counters();
      reset_pending_ = true;
      spdlog::info("RESET_COUNTERS (request {})", msg.request_id);
      return;
    case control_t::SHUTDOWN:
      ++control_acted_;
      spdlog::info("SHUTDOWN (request {})", msg.request_id);
      request_stop();
      return;
    default:
      // Meant for the compensator; refused only when addressed to the bridge by name.
      if (msg.target == "bridge") {
        ++control_refused_;
        spdlog::warn("control command {} (request {}) is not one the bridge knows; ignored", msg.command,
                     msg.request_id);
      }
      return;
  }
}

void BridgeService::publish_samples() noexcept {
  while (const auto s = rt_.pop_sample()) {
    sample_msg_.utime = s->utime;
    sample_msg_.seq = s->seq;
    sample_msg_.u_V = s->u_V;
    sample_msg_.y_m = s->y_m;
    sample_msg_.flags = s->flags;
    sensor_pub_.publish(sample_msg_);
    sent_.record(s->seq, monotonic_now_ns());
  }
}

int BridgeService::run() {
  for (const std::string& line : describe(settings_)) spdlog::info("{}", line);
  spdlog::info("channels: {} out, {} and {} in", sensor_pub_.channel(), commands_.channel(), control_.channel());
  rt_.start();
  while (!rt_.started()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  spdlog::info("real-time thread: {}; {}", rt_.priority_status().detail, rt_.affinity_status().detail);

  spdlog::info("started in the safe state ({} V); {}", settings_.limits.safe_u_V,
               settings_.auto_arm ? "arms when commands flow" : "waiting for ARM on HX_CONTROL");

  using clock = std::chrono::steady_clock;
  const auto started = clock::now();
  auto next_report = started + std::chrono::seconds(1);
  bool awaiting_report = false;
  int lcm_errors = 0;
  pollfd fds[3] = {{lcm_.getFileno(), POLLIN, 0}, {rt_.wake_fd(), POLLIN, 0}, {stop_fd(), POLLIN, 0}};
  const nfds_t nfds = stop_fd() >= 0 ? 3 : 2;
  while (!stop_requested()) {
    const timespec timeout{0, 20'000'000};  // status and --seconds are checked at least every 20 ms
    const int ready = ppoll(fds, nfds, &timeout, nullptr);
    if (ready < 0 && errno != EINTR) ++lcm_errors;
    if (fds[1].revents & POLLIN) {
      std::uint64_t count = 0;
      [[maybe_unused]] const ssize_t n = ::read(rt_.wake_fd(), &count, sizeof count);
    }
    publish_samples();
    if (fds[0].revents & POLLIN) {
      for (int i = 0; i < 256; ++i) {
        const int rc = lcm_.handleTimeout(0);
        if (rc < 0) ++lcm_errors;
        if (rc <= 0) break;
      }
    }
    const auto now = clock::now();
    if ((now >= next_report || reset_pending_) && !awaiting_report) {
      rt_.reports().request();
      awaiting_report = true;
      if (now >= next_report) next_report += std::chrono::seconds(1);
    }
    if (awaiting_report) {
      if (const RtReport* r = rt_.reports().take()) {
        report(*r, wall_utime(), false);
        rt_.reports().release();
        awaiting_report = false;
      }
    }
    if (settings_.run_seconds > 0 && now - started >= std::chrono::duration<double>(settings_.run_seconds)) {
      spdlog::info("--seconds {} reached", settings_.run_seconds);
      request_stop();
    }
  }

  spdlog::info("stopping{}", stop_signal() ? fmt::format(" on signal {}", stop_signal()) : std::string());
  // One last report from the real-time thread before it stops.
  if (!awaiting_report) rt_.reports().request();
  const RtReport* last = nullptr;
  for (int i = 0; i < 100 && last == nullptr; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    last = rt_.reports().take();
  }
  rt_.stop();
  publish_samples();
  if (last == nullptr) last = rt_.reports().take();
  if (last != nullptr) {
    report(*last, wall_utime(), true);
    log_summary(*last);
  }
  return lcm_errors > 0 ? 1 : 0;
}

void BridgeService::report(const RtReport& rt, std::int64_t utime, bool stopping) {
  if (reset_pending_) {
    baseline_.core = rt.core;
    baseline_.skipped = rt.ticks_skipped;
    baseline_.dropped = rt.samples_dropped;
    reset_pending_ = false;
  }
  // Late fraction of this report period, over the ticks that were armed.
  const std::uint64_t late = rt.core.late - previous_core_.late;
  const std::uint64_t armed_ticks = late + (rt.core.applied - previous_core_.applied);
  const double late_fraction = armed_ticks > 0 ? static_cast<double>(late) / static_cast<double>(armed_ticks) : 0.0;
  const std::uint64_t dropped = rt.samples_dropped - previous_dropped_;
  previous_core_ = rt.core;
  previous_dropped_ = rt.samples_dropped;
  if (rt.core.watchdog_trips != trips_reported_) {
    trips_reported_ = rt.core.watchdog_trips;
    safe_reason_ = fmt::format("watchdog: no command for more than {} s, tripped at tick {}; re-arm via HX_CONTROL",
                               settings_.limits.watchdog_s, rt.last_trip_tick);
    spdlog::warn("{}", safe_reason_);
  }

  std::int8_t state = service_status_t::HEALTHY;
  std::string detail;
  if (stopping) {
    state = service_status_t::STOPPING;
    detail = "stopping";
  } else if (!rt.armed) {
    state = service_status_t::SAFE;
    detail = safe_reason_;
  } else if (late_fraction > settings_.degraded_late_fraction) {
    state = service_status_t::DEGRADED;
    detail = fmt::format("late fraction {:.3g} % > {:.3g} %", 100.0 * late_fraction,
                         100.0 * settings_.degraded_late_fraction);
  } else if (dropped > 0) {
    state = service_status_t::DEGRADED;
    detail = fmt::format("{} samples dropped: the I/O thread fell behind", dropped);
  }
  if (rt.armed) safe_reason_ = "not armed";  // the next safe state says its own reason
  detail += fmt::format("{}backend {}, u {:.4g} V, gain x{:.4f}, late {:.3g} % this period", detail.empty() ? "" : "; ",
                        rt_.backend().name(), rt.u_applied_V, rt.gain_scale, 100.0 * late_fraction);

  const BridgeCounters c = core_since(rt.core, baseline_.core);
  status_.begin(state, detail);
  status_.counter("ticks", c.ticks);
  status_.counter("applied", c.applied);
  status_.counter("late", c.late);
  status_.counter("stale", c.stale);
  status_.counter("rejected_nonfinite", c.rejected_nonfinite);
  status_.counter("rejected_future", c.rejected_future);
  status_.counter("clamped", c.clamped);
  status_.counter("slew_limited", c.slew_limited);
  status_.counter("watchdog_trips", c.watchdog_trips);
  status_.counter("ignored_disarmed", c.ignored_disarmed);
  status_.counter("ticks_skipped", rt.ticks_skipped - baseline_.skipped);
  status_.counter("samples_dropped", rt.samples_dropped - baseline_.dropped);
  status_.counter("command_queue_full", command_queue_full_ - baseline_.queue_full);
  status_.counter("control_acted", control_acted_ - baseline_.acted);
  status_.counter("control_refused", control_refused_ - baseline_.refused);
  status_.counter("armed", rt.armed ? 1 : 0);
  status_.counter("late_ppm_period", static_cast<std::uint64_t>(late_fraction * 1e6));
  if (rt.lateness.count() > 0) {  // the timer's wake-up lateness this period
    status_.counter("timer_lateness_p50_ns", static_cast<std::uint64_t>(rt.lateness.percentile(0.5)));
    status_.counter("timer_lateness_p99_ns", static_cast<std::uint64_t>(rt.lateness.percentile(0.99)));
    status_.counter("timer_lateness_max_ns", static_cast<std::uint64_t>(rt.lateness.max_ns()));
  }
  const ResourceUsage usage = read_resource_usage();
  status_.counter("cpu_user_us", static_cast<std::uint64_t>(usage.user_cpu_s * 1e6));
  status_.counter("cpu_system_us", static_cast<std::uint64_t>(usage.system_cpu_s * 1e6));
  status_.counter("peak_rss_kB", static_cast<std::uint64_t>(usage.peak_rss_bytes / 1024));
  status_.endpoint("command", counters_since(commands_.counters(), baseline_.commands));
  status_.endpoint("control", counters_since(control_.counters(), baseline_.control));
  status_.publisher("sensor", counters_since(sensor_pub_.counters(), baseline_.sensor));
  status_.add_rejected(static_cast<std::int64_t>(c.rejected_nonfinite + c.rejected_future +
                                                 (command_queue_full_ - baseline_.queue_full) +
                                                 (control_refused_ - baseline_.refused)));
  status_.late(static_cast<std::int64_t>(c.late));
  status_.loop_timing(rt.work);
  status_.latency(latency_);
  status_.publish(utime);
  latency_.reset();
}

void BridgeService::log_summary(const RtReport& rt) const {
  const BridgeCounters& c = rt.core;
  const double armed_ticks = static_cast<double>(c.applied + c.late);
  spdlog::info("summary: {} ticks ({} skipped), {} commands applied, {} late ({:.3g} % of armed ticks), {} stale, "
               "{} clamped, {} slew-limited, {} watchdog trips, {} non-finite and {} too-far-ahead rejected",
               c.ticks, rt.ticks_skipped, c.applied, c.late, armed_ticks > 0 ? 100.0 * static_cast<double>(c.late) / armed_ticks : 0.0,
               c.stale, c.clamped, c.slew_limited, c.watchdog_trips, c.rejected_nonfinite, c.rejected_future);
  if (latency_total_.count() > 0) {
    spdlog::info("summary: sample-to-command latency p50 {:.1f} us, p99 {:.1f} us, max {:.1f} us over {} commands",
                 latency_total_.percentile(0.5) / 1e3, latency_total_.percentile(0.99) / 1e3,
                 static_cast<double>(latency_total_.max_ns()) / 1e3, latency_total_.count());
  }
  spdlog::info("summary: {} samples published, {} commands received ({} rejected), {} dropped samples",
               sensor_pub_.counters().published, commands_.counters().received,
               commands_.counters().rejected_total(), rt.samples_dropped);
}

}  // namespace hystloop
