#include "compensator/compensator_service.hpp"

#include <chrono>
#include <cmath>

#include <spdlog/spdlog.h>

#include "compensator/trajectory_message.hpp"
#include "core/periodic_timer.hpp"
#include "core/process.hpp"
#include "runtime/counter_baseline.hpp"
#include "runtime/io_loop.hpp"

namespace hystloop {
namespace {

// A sample seq this far below the last one means the bridge restarted its clock.
constexpr std::int64_t kRestartTicks = 1000;

template <class T>
typename Subscription<T>::Options queue_of(int capacity) {
  typename Subscription<T>::Options o;
  o.queue_capacity = capacity;
  return o;
}

FeedbackGains held(FeedbackGains g) noexcept {
  g.kp = g.ki = g.kd = 0.0;
  return g;
}

}  // namespace

CompensatorService::CompensatorService(const CompensatorSettings& settings, lcm::LCM& lcm, const ChannelNames& channels)
    : settings_(settings),
      lcm_(lcm),
      compensator_(std::in_place, settings.control),
      command_pub_(lcm, channels.command),
      samples_(lcm, channels.sensor, [this](const sensor_sample_t& m, std::int64_t t) { on_sample(m, t); },
               queue_of<sensor_sample_t>(settings.sample_queue_capacity)),
      trajectories_(lcm, channels.trajectory, [this](const trajectory_t& m, std::int64_t) { on_trajectory(m); }),
      params_(lcm, channels.params, [this](const mem_params_t& m, std::int64_t) { on_params(m); }),
      control_(lcm, channels.control, [this](const control_t& m, std::int64_t) { on_control(m); }),
      status_(lcm, channels.status, "compensator"),
      gains_(settings.control.feedback) {
  pending_trajectory_ = settings.trajectory;  // the configured reference starts with the first sample
  baseline_ = collect_counters();
  for (auto& [name, value] : baseline_) value = 0;
}

void CompensatorService::on_sample(const sensor_sample_t& msg, std::int64_t recv_utime) noexcept {
  const std::int64_t start_ns = monotonic_now_ns();
  if (have_sample_ && msg.seq + kRestartTicks < last_sample_seq_) restart_control_law();
  last_sample_utime_ = msg.utime;
  last_sample_seq_ = msg.seq;
  ++samples_in_period_;

  // While the bridge holds its safe voltage, the error says nothing about our commands:
  // integrating it would wind the feedback up for the moment the bridge is re-armed.
  const bool safe = (msg.flags & sensor_sample_t::SAFE_STATE) != 0;
  if (safe != feedback_held_) {
    feedback_held_ = safe;
    if (safe) ++counters_.feedback_holds;
    try {
      compensator_->set_gains(safe ? held(gains_) : gains_);
    } catch (...) {  // the gains were validated when they were set
    }
  }

  const auto out = compensator_->update({msg.seq, msg.u_V, msg.y_m});
  if (!have_sample_) {
    have_sample_ = true;
    if (pending_trajectory_) {  // now the loop time is known
      const TrajectorySpec spec = *pending_trajectory_;
      pending_trajectory_.reset();
      try {
        apply_trajectory(spec, pending_start_utime_);
      } catch (...) {
        ++counters_.trajectory_refused;
      }
    }
  }
  if (out) {
    command_.utime = wall_utime();
    command_.seq = out->seq;
    command_.sample_seq = out->sample_seq;
    command_.u_V = out->u_V;
    command_.u_ff_V = out->u_ff_V;
    command_.u_fb_V = out->u_fb_V;
    command_.y_ref_m = out->y_ref_m;
    command_.params_version = out->params_version;
    command_.mode = static_cast<std::int8_t>(out->mode);
    if (command_pub_.publish(command_)) ++counters_.commands_published;
    // recv_utime is LCM's receive time on this host's clock; a value outside [0, 10 s) is not a latency.
    const std::int64_t latency_us = wall_utime() - recv_utime;
    if (latency_us >= 0 && latency_us < 10'000'000) latency_.add(latency_us * 1000);
  }
  work_.add(monotonic_now_ns() - start_ns);
}

void CompensatorService::apply_trajectory(TrajectorySpec spec, std::int64_t start_utime) {
  if (!have_sample_) {
    spec.validate();
    pending_trajectory_ = spec;
    pending_start_utime_ = start_utime;
    return;
  }
  Compensator& c = *compensator_;
  const double t_next = c.loop_time(c.last_seq() + c.config().lead_ticks + 1);
  const double here = evaluate(trajectory_, t_next - c.config().dt_s);
  bool now = start_utime == 0;
  if (!now) {
    spec.start_s = loop_time_of_utime(start_utime, last_sample_utime_, last_sample_seq_, c.config().dt_s);
    if (spec.start_s - spec.blend_s < t_next) {
      ++counters_.trajectory_late_start;
      now = true;
    }
  }
  if (now) {
    c.start_trajectory_now(spec);
    spec.start_s = t_next + spec.blend_s;
    spec.hold_m = std::isfinite(here) ? here : 0.0;
  } else {
    spec.hold_m = std::isfinite(here) ? here : 0.0;
    c.set_trajectory(spec);
  }
  trajectory_ = spec;
  ++counters_.trajectories;
}

void CompensatorService::on_trajectory(const trajectory_t& msg) {
  if (msg.version == trajectory_version_) {
    ++counters_.trajectory_repeats;
    return;
  }
  try {
    apply_trajectory(trajectory_from_message(msg), msg.start_utime);
    trajectory_version_ = msg.version;
    spdlog::info("trajectory v{}: shape {}, amplitude {:.4g} m, offset {:.4g} m, {} Hz, blend {} s", msg.version,
                 msg.shape, msg.amplitude_m, msg.offset_m, msg.frequency_Hz, msg.blend_s);
  } catch (const std::exception& e) {
    ++counters_.trajectory_refused;
    spdlog::warn("trajectory v{} refused: {}", msg.version, e.what());
  }
}

void CompensatorService::on_params(const mem_params_t& msg) {
  if (!msg.valid) {
    ++counters_.params_invalid;
    spdlog::warn("MEM parameters v{} from '{}' are marked invalid; not used", msg.version, msg.source);
    return;
  }
  if (msg.version <= offered_version_) {
    ++counters_.params_stale;
    return;
  }
  MemParams p;
  p.c1 = msg.c1;
  p.c2 = msg.c2;
  p.c3 = msg.c3;
  try {
    compensator_->offer_mem_params(p, msg.version);
    offered_version_ = msg.version;
    spdlog::info("MEM parameters v{} from '{}' accepted (c1 {:.6g}, c2 {:.6g}, c3 {:.6g}, residual {:.3g} m); "
                 "swapped in at the next reversal",
                 msg.version, msg.source, msg.c1, msg.c2, msg.c3, msg.residual_m);
  } catch (const ParameterError& e) {
    ++counters_.params_refused;
    spdlog::warn("MEM parameters v{} refused: {}", msg.version, e.what());
  }
}

void CompensatorService::on_control(const control_t& msg) {
  if (!filter_.accept(msg)) return;
  auto refuse = [&](const std::string& why) {
    ++counters_.control_refused;
    spdlog::warn("control request {} (command {}) refused: {}", msg.request_id, msg.command, why);
  };
  try {
    switch (msg.command) {
      case control_t::SET_MODE:
        if (msg.mode < actuator_command_t::MODE_OFF || msg.mode > actuator_command_t::MODE_KATALENIC) {
          return refuse("mode " + std::to_string(msg.mode) + " is not selectable (off, linear, mem, pi, katalenic)");
        }
        compensator_->set_mode(static_cast<FeedforwardMode>(msg.mode));
        spdlog::info("mode {} (request {})", to_string(compensator_->mode()), msg.request_id);
        break;
      case control_t::SET_GAINS: {
        FeedbackGains g = gains_;
        g.kp = msg.kp;
        g.ki = msg.ki;
        g.kd = msg.kd;
        g.validate();
        if (!feedback_held_) compensator_->set_gains(g);
        gains_ = g;
        spdlog::info("gains kp {}, ki {} 1/s, kd {} s (request {})", g.kp, g.ki, g.kd, msg.request_id);
        break;
      }
      case control_t::START_EXPERIMENT: {
        const ExperimentSpec e = make_experiment_spec(msg.experiment, msg.experiment_amplitude_V,
                                                      msg.experiment_offset_V, msg.experiment_frequency_Hz,
                                                      msg.experiment_duration_s);
        const bool queued = compensator_->experiment_running();
        compensator_->start_experiment(e);
        spdlog::info("experiment {} {} V + {} V at {} Hz for {} s {} (request {})", msg.experiment, e.amplitude_V,
                     e.offset_V, e.frequency_hz, e.duration_s,
                     queued ? "queued, " + std::to_string(compensator_->experiments_queued()) + " waiting" : "started",
                     msg.request_id);
        break;
      }
      case control_t::STOP_EXPERIMENT:
        spdlog::info("experiment stopped, {} queued dropped (request {})", compensator_->experiments_queued(),
                     msg.request_id);
        compensator_->stop_experiment();
        break;
      case control_t::RESET_COUNTERS:
        baseline_ = collect_counters();
        endpoint_base_ = {samples_.counters(), trajectories_.counters(), params_.counters(), control_.counters(),
                          command_pub_.counters()};
        spdlog::info("RESET_COUNTERS (request {})", msg.request_id);
        break;
      case control_t::SHUTDOWN:
        spdlog::info("SHUTDOWN (request {})", msg.request_id);
        request_stop();
        break;
      default:  // the bridge's (ARM, DISARM)
        if (msg.target == "compensator") return refuse("not a compensator command");
        return;
    }
    ++counters_.control_acted;
  } catch (const std::exception& e) {
    refuse(e.what());
  }
}

void CompensatorService::restart_control_law() {
  // The bridge restarted (its seq went back): a new control law with what is in force now.
  CompensatorConfig config = settings_.control;
  const Compensator& old = *compensator_;
  config.mem = old.mem_params();
  config.mode = old.experiment_running() ? settings_.control.mode : old.mode();
  config.feedback = gains_;
  compensator_.emplace(config);
  feedback_held_ = false;
  have_sample_ = false;
  TrajectorySpec spec = trajectory_;
  spec.hold_m = 0.0;
  pending_trajectory_ = spec;
  trajectory_ = TrajectorySpec{};
  pending_start_utime_ = 0;
  ++counters_.bridge_restarts;
}

std::vector<std::pair<std::string, std::uint64_t>> CompensatorService::collect_counters() const {
  const CompensatorCounters& c = compensator_->counters();
  const CompensatorServiceCounters& s = counters_;
  return {{"samples", c.samples},
          {"commands_published", s.commands_published},
          {"gaps", c.gaps},
          {"out_of_order", c.out_of_order},
          {"nonfinite_outputs", c.nonfinite_outputs},
          {"params_accepted", c.params_accepted},
          {"params_rejected", c.params_rejected + s.params_refused},
          {"params_invalid", s.params_invalid},
          {"params_stale", s.params_stale},
          {"params_swapped", c.params_swapped},
          {"trajectories", s.trajectories},
          {"trajectory_repeats", s.trajectory_repeats},
          {"trajectory_refused", s.trajectory_refused},
          {"trajectory_late_start", s.trajectory_late_start},
          {"control_acted", s.control_acted},
          {"control_refused", s.control_refused},
          {"feedback_holds", s.feedback_holds},
          {"bridge_restarts", s.bridge_restarts}};
}

void CompensatorService::report(std::int64_t utime, bool stopping) {
  const auto counters = collect_counters();
  const Compensator& c = *compensator_;
  if (c.counters().params_swapped != swaps_reported_) {
    swaps_reported_ = c.counters().params_swapped;
    spdlog::info("MEM parameters v{} in use (c1 {:.6g}, c2 {:.6g}, c3 {:.6g})", c.params_version(), c.mem_params().c1,
                 c.mem_params().c2, c.mem_params().c3);
  }

  std::int8_t state = service_status_t::HEALTHY;
  std::string detail;
  if (stopping) {
    state = service_status_t::STOPPING;
    detail = "stopping; ";
  } else if (!have_sample_) {
    state = service_status_t::STARTING;
    detail = "waiting for samples; ";
  } else if (samples_in_period_ == 0) {
    state = service_status_t::DEGRADED;
    detail = "no samples from the bridge this period; ";
  }
  const MemParams& m = c.mem_params();
  detail += fmt::format("mode {}, params v{} c1={:.6g} c2={:.6g} c3={:.6g}, feedback kp={} ki={} kd={}{}{}",
                        to_string(c.experiment_running() ? FeedforwardMode::kExperiment : c.mode()), c.params_version(),
                        m.c1, m.c2, m.c3, gains_.kp, gains_.ki, gains_.kd,
                        feedback_held_ ? ", bridge in safe state: feedback held" : "",
                        c.experiment_running() ? ", experiment running" : "");
  status_.begin(state, detail);
  std::uint64_t semantic_rejects = 0;
  for (std::size_t i = 0; i < counters.size(); ++i) {
    const std::uint64_t value = counters[i].second - baseline_[i].second;
    status_.counter(counters[i].first, value);
    const std::string& n = counters[i].first;
    if (n == "params_rejected" || n == "params_invalid" || n == "trajectory_refused" || n == "control_refused") {
      semantic_rejects += value;
    }
  }
  const ResourceUsage usage = read_resource_usage();
  status_.counter("cpu_user_us", static_cast<std::uint64_t>(usage.user_cpu_s * 1e6));
  status_.counter("cpu_system_us", static_cast<std::uint64_t>(usage.system_cpu_s * 1e6));
  status_.counter("peak_rss_kB", static_cast<std::uint64_t>(usage.peak_rss_bytes / 1024));
  status_.endpoint("sensor", counters_since(samples_.counters(), endpoint_base_.sensor));
  status_.endpoint("trajectory", counters_since(trajectories_.counters(), endpoint_base_.trajectory));
  status_.endpoint("params", counters_since(params_.counters(), endpoint_base_.params));
  status_.endpoint("control", counters_since(control_.counters(), endpoint_base_.control));
  status_.publisher("command", counters_since(command_pub_.counters(), endpoint_base_.command));
  status_.add_rejected(static_cast<std::int64_t>(semantic_rejects));
  status_.loop_timing(work_);
  status_.latency(latency_);
  status_.publish(utime);
  latency_total_.merge(latency_);
  latency_.reset();
  work_.reset();
  samples_in_period_ = 0;
}

int CompensatorService::run() {
  for (const std::string& line : describe(settings_)) spdlog::info("{}", line);
  spdlog::info("channels: {} in, {} out; {}, {}, {} in", samples_.channel(), command_pub_.channel(),
               trajectories_.channel(), params_.channel(), control_.channel());
  const auto started = std::chrono::steady_clock::now();
  IoLoopOptions options;
  options.poll_timeout = std::chrono::microseconds(20000);
  const int errors = run_io_loop(lcm_, options, [&](std::int64_t utime) {
    report(utime, false);
    if (settings_.run_seconds > 0 &&
        std::chrono::steady_clock::now() - started >= std::chrono::duration<double>(settings_.run_seconds)) {
      spdlog::info("--seconds {} reached", settings_.run_seconds);
      request_stop();
    }
  });
  spdlog::info("stopping{}", stop_signal() ? fmt::format(" on signal {}", stop_signal()) : std::string());
  report(wall_utime(), true);
  const CompensatorCounters& c = compensator_->counters();
  spdlog::info("summary: {} samples, {} commands published, {} gaps, {} out of order, params {} accepted / {} refused "
               "/ {} swapped, {} invalid sets ignored",
               c.samples, counters_.commands_published, c.gaps, c.out_of_order, c.params_accepted,
               c.params_rejected + counters_.params_refused, c.params_swapped, counters_.params_invalid);
  if (latency_total_.count() > 0) {
    spdlog::info("summary: sample received -> command published p50 {:.1f} us, p99 {:.1f} us, max {:.1f} us",
                 latency_total_.percentile(0.5) / 1e3, latency_total_.percentile(0.99) / 1e3,
                 static_cast<double>(latency_total_.max_ns()) / 1e3);
  }
  return errors > 0 ? 1 : 0;
}

}  // namespace hystloop
