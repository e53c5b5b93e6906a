#include "reidentifier/reident_service.hpp"

#include <chrono>
#include <cmath>
#include <string>
#include <utility>

#include <spdlog/spdlog.h>

#include "core/clock.hpp"
#include "core/process.hpp"
#include "lcm/feedforward_mode.hpp"
#include "models/axis_coupling.hpp"
#include "runtime/io_loop.hpp"
#include "runtime/model_params_message.hpp"

namespace hystloop {

namespace {
std::int64_t steady_us() noexcept { return monotonic_ns() / 1000; }

// DEGRADED for this long after a set with our publisher id that we never published [us] (and
// beyond, while the compensator applies it): long enough to be seen in the 1 Hz status.
constexpr std::int64_t kForgedDegradedUs = 30'000'000;

ModelParamSet initial_model(const ReidentOptions& options) {
  ModelParamSet set;
  set.kind = ModelKind::mem;  // the compensator's default, configured from the same mem.* keys
  set.mem = options.initial;
  return set;
}

// Logs refusals on the worker thread, right after evaluate: the I/O thread never formats one.
// A steady plant is refused every period (no_improvement): a reason is logged at info when it
// differs from the previous refusal's, or once a minute while it repeats; at debug otherwise.
RefitWorker::OnEvaluated refusal_logger() {
  return [last = FitStatus::ok, last_info_ns = std::int64_t{0},
          repeats = std::uint64_t{0}](const RefitResult& r) mutable {
    if (r.outcome.accepted) {
      last = FitStatus::ok;
      return;
    }
    const std::int64_t now = monotonic_ns();
    const bool news = r.outcome.status != last || now - last_info_ns >= 60'000'000'000;
    const auto level = news ? spdlog::level::info : spdlog::level::debug;
    spdlog::log(level, "refit refused ({}): {} [window {} samples from seq {}, {:.1f} ms{}]",
                to_string(r.outcome.status), r.outcome.reason, r.window_samples, r.window_first_seq, r.duration_s * 1e3,
                news && repeats > 0 ? fmt::format("; {} repeats at debug level before this", repeats) : std::string());
    if (news) {
      last_info_ns = now;
      repeats = 0;
    } else {
      ++repeats;
    }
    last = r.outcome.status;
  };
}
}  // namespace

std::string ReidentService::process_name(int axis) {
  // x keeps the name every tool, test and deploy script knows; the others say their axis.
  return axis == 0 ? std::string(kProcessName) : std::string(kProcessName) + "-" + std::string(axis_name(axis));
}

ReidentService::ReidentService(lcm::LCM& lcm, const ChannelNames& names, const ReidentOptions& options,
                               std::vector<RigLimitsOwn> rig_limits)
    : lcm_(lcm),
      options_(options),
      process_(process_name(options.axis)),
      own_source_(process_ + "@" + host_name()),
      core_(std::make_unique<ReidentCore>(options, own_source_, true, refusal_logger())),
      params_out_(lcm, names.params),
      chooser_(
          std::make_unique<ModelChooser>(options.models, initial_model(options), core_->estimator().make_window())),
      model_out_(lcm, names.model),
      status_(lcm, names.status, process_),
      control_filter_(process_) {
  core_->hold(options.hold);
  if (options.hold) spdlog::info("holding the set in use from the start (reidentifier.hold): nothing is published");
  out_.source = own_source_;
  out_.publisher_id = core_->in_use().own_publisher_id();
  out_.axis = static_cast<std::int8_t>(options.axis);  // the compensator offers a set only to the axis it names
  model_msg_.source = own_source_;
  model_msg_.publisher_id = core_->in_use().own_publisher_id();
  model_msg_.axis = static_cast<std::int8_t>(options.axis);
  reserve_storage(model_msg_);
  Subscription<sensor_block_t>::Options sensor_options;
  sensor_options.queue_capacity = static_cast<int>(options.lcm_queue);
  sensor_options.on_reject = [this](RejectReason reason) {
    if (reason == RejectReason::kNonFinite || reason == RejectReason::kOutOfRange) {
      // Its size is unknown (refused before use): the bridge's blocks have one size, the last one's.
      core_->on_refused_block(sensor_->latest().n_ticks, steady_us());
    }
  };
  sensor_ = std::make_unique<Subscription<sensor_block_t>>(
      lcm, names.sensor, [this](const sensor_block_t& msg, std::int64_t) { on_sensor_block(msg); }, sensor_options);
  command_ = std::make_unique<Subscription<command_block_t>>(
      lcm, names.command, [this](const command_block_t& msg, std::int64_t) { core_->on_command_block(msg); },
      Subscription<command_block_t>::Options{.queue_capacity = sensor_options.queue_capacity, .on_reject = {}});
  params_in_ = std::make_unique<Subscription<mem_params_t>>(
      lcm, names.params, [this](const mem_params_t& msg, std::int64_t) { on_params(msg); });
  control_ = std::make_unique<Subscription<control_t>>(lcm, names.control,
                                                       [this](const control_t& msg, std::int64_t) { on_control(msg); });
  // A new reference for our axis: the window starts again where it holds another line
  // (ReidentCore::on_new_reference). Only a trajectory that differs from the last one requested
  // counts: the same line again (a rig's configured reference requested by a script) changes no
  // loop. A request the compensator then refuses costs a window's wait for the next refit.
  trajectory_ = std::make_unique<
      Subscription<trajectory_t>>(lcm, names.trajectory, [this](const trajectory_t& msg, std::int64_t) {
    if (msg.axis != options_.axis || msg.version == std::exchange(trajectory_version_, msg.version)) return;
    const std::array<double, 4> line{static_cast<double>(msg.shape), msg.amplitude_m, msg.frequency_Hz, msg.offset_m};
    const bool other = last_line_ && *last_line_ != line;
    last_line_ = line;
    if (other) core_->on_new_reference();
  });
  scan_ = std::make_unique<Subscription<scan_t>>(lcm, names.scan, [this](const scan_t& msg, std::int64_t) {
    if (msg.version == std::exchange(scan_version_, msg.version)) return;
    core_->on_new_reference();
  });
  rig_check_ = std::make_unique<RigCheck>(lcm, names.status, std::move(rig_limits), process_);
}

void ReidentService::on_sensor_block(const sensor_block_t& msg) noexcept {
  const std::int64_t t0 = monotonic_ns();
  if (!core_->on_sensor_block(msg, t0 / 1000)) log_wrong_axes(msg.n_axes, t0);
  block_cost_.add(monotonic_ns() - t0);
}

void ReidentService::log_wrong_axes(std::int8_t n_axes, std::int64_t now_ns) noexcept {
  const LogLimiter::Gate g = log_limiter_.allow(kLogWrongAxes, now_ns);
  if (!g) return;
  try {  // off the per-sample path: a refused block, at most one line a second
    std::string carried;
    for (int a = 0; a < n_axes; ++a) carried += (a == 0 ? "" : ", ") + std::string(axis_name(a));
    spdlog::warn(
        "HX_SENSOR block of {} {} ({}) has no {}, the axis this re-identifier fits (reidentifier.axis): "
        "refused whole, counted (sensor_blocks_wrong_axes){}",
        n_axes, n_axes == 1 ? "axis" : "axes", carried, axis_name(options_.axis), suppressed_note(g));
  } catch (...) {  // out of memory while formatting: the count still says it
  }
}

void ReidentService::on_params(const mem_params_t& msg) {
  const MemParams p{msg.c1, msg.c2, msg.c3};
  const std::uint64_t implausible_before = core_->counters().get(ReidentCounter::params_implausible);
  const ParamsOffer offer = core_->on_params(msg.axis, p, msg.version, msg.publisher_id, msg.valid, msg.source);
  // Counted by the core (params_adopted, _stale, _invalid, _implausible); logged at most once a second per kind.
  const auto id = static_cast<std::uint64_t>(msg.publisher_id);
  const auto log = [&](LogReason reason, spdlog::level::level_enum level, const std::string& what) {
    if (const LogLimiter::Gate g = log_limiter_.allow(reason, monotonic_ns())) {
      spdlog::log(level, "params version {} from '{}' (publisher {:x}) {}{}", msg.version, escape_wire(msg.source), id,
                  what, suppressed_note(g));
    }
  };
  if (core_->counters().get(ReidentCounter::params_implausible) != implausible_before) {
    return log(kLogInvalid, spdlog::level::warn, "not adopted: " + core_->implausible_reason());
  }
  if (offer == ParamsOffer::other_axis) {
    log(kLogOtherAxis, spdlog::level::debug,
        fmt::format("ignored: for {}, another re-identifier's axis (this one fits {})", axis_name(msg.axis),
                    axis_name(options_.axis)));
  } else if (offer == ParamsOffer::adopted) {
    log(kLogAdopted, spdlog::level::info,
        fmt::format("in use now: c1 {:.6g} m/V, c2 {:.6g}, c3 {:.6g}", msg.c1, msg.c2, msg.c3));
  } else if (offer == ParamsOffer::stale) {
    log(kLogStale, spdlog::level::debug, "ignored: not newer than the last from it");
  } else if (offer == ParamsOffer::invalid) {
    log(kLogInvalid, spdlog::level::info, "not used: marked invalid or outside the model's domain");
  } else if (offer == ParamsOffer::forged) {
    forged_seen_us_ = steady_us();
    if (!forged_logged_) {  // once: the rest are counted (params_forged) and in the status detail
      forged_logged_ = true;
      spdlog::warn(
          "params version {} from '{}' carries our publisher id {:x}, but we never published that version "
          "(forged?): not used; further ones are counted (params_forged), not logged",
          msg.version, escape_wire(msg.source), id);
    }
  }
}

CounterSet::Entries ReidentService::counter_entries() {
  const ReidentCounters& c = core_->counters();
  CounterSet::Entries entries;
  entries.reserve(kReidentCounterCount + ModelChooser::kCounters + 2);
  for (std::size_t i = 0; i < kReidentCounterCount; ++i) entries.emplace_back(std::string(counter_name(i)), c.at(i));
  for (std::size_t i = 0; i < ModelChooser::kCounters; ++i) {
    entries.emplace_back(ModelChooser::counter_name(i), chooser_->count(static_cast<ModelChooser::Counter>(i)));
  }
  entries.emplace_back("refits_rejected", c.rejected_total());
  entries.emplace_back("params_forged", core_->in_use().forged_sets());
  return entries;
}

void ReidentService::on_control(const control_t& msg) {
  if (!control_filter_.accept(msg)) return;
  if (msg.command == control_t::SET_MODE && msg.target == process_) {
    pin_model(msg);
  } else if (msg.command == control_t::HOLD_PARAMS || msg.command == control_t::RELEASE_PARAMS) {
    const bool on = msg.command == control_t::HOLD_PARAMS;
    core_->hold(on);
    acks_.acted(msg.request_id);
    spdlog::info("{} (request {})",
                 on ? "holding the set in use: refits are judged and reported, nothing is published"
                    : "released: refits that beat the set in use are published again",
                 msg.request_id);
  } else if (msg.command == control_t::SHUTDOWN) {
    acks_.acted(msg.request_id);
    spdlog::info("shutdown requested (request {})", msg.request_id);  // once: the service stops
    request_stop();
  } else if (msg.command == control_t::RESET_COUNTERS) {
    acks_.acted(msg.request_id);
    if (const LogLimiter::Gate g = log_limiter_.allow(kLogReset, monotonic_ns())) {
      spdlog::info("counters reset (request {}){}", msg.request_id, suppressed_note(g));
    }
    core_->reset_refit_time();
    reported_.rebase(counter_entries());
    reported_.rebase("sensor", sensor_->counters());
    reported_.rebase("command", command_->counters());
    reported_.rebase("params_in", params_in_->counters());
    reported_.rebase("control", control_->counters());
    reported_.rebase("trajectory", trajectory_->counters());
    reported_.rebase("scan", scan_->counters());
    reported_.rebase("params_out", params_out_.counters());
    reported_.rebase("model_out", model_out_.counters());
  }
  if (msg.target == process_ && !acks_.due()) {
    acks_.refused(msg.request_id,
                  "command " + std::to_string(msg.command) +
                      " is not the re-identifier's (pin-model, hold, reset-counters, shutdown)",
                  wall_utime());
  }
  // Its sender waits for the answer: at once, unless a report went out within StatusReporter's
  // interval; then on_tick sends it when the interval has passed.
  if (acks_.due() && status_.immediate_allowed(monotonic_ns())) publish_status(steady_us(), false);
}

void ReidentService::publish_decision(const RefitDecision& d) {
  using Kind = RefitDecision::Kind;
  if (d.kind == Kind::none) return;
  if (d.kind == Kind::held) {
    spdlog::info(
        "refit held (not published): c1 {:.6g} m/V, c2 {:.6g}, c3 {:.6g}; held-out RMS {:.3g} m vs {:.3g} m in use",
        d.candidate.c1, d.candidate.c2, d.candidate.c3, d.holdout_rms_candidate_m, d.holdout_rms_in_use_m);
    return;
  }
  if (d.kind == Kind::superseded) {
    spdlog::info("refit accepted but not adopted: the set in use changed to version {} meanwhile",
                 core_->in_use().version());
    return;
  }
  if (d.kind == Kind::refused && !(options_.publish_invalid && d.fitted)) return;
  const bool valid = d.kind == Kind::accepted;
  out_.utime = wall_utime();
  out_.version = valid ? d.version : core_->claim_diagnostic_version();
  out_.c1 = d.candidate.c1;
  out_.c2 = d.candidate.c2;
  out_.c3 = d.candidate.c3;
  out_.residual_m = d.holdout_rms_candidate_m > 0.0 ? d.holdout_rms_candidate_m : d.fit_residual_rms_m;
  out_.samples_used = static_cast<std::int64_t>(d.samples_used);
  out_.window_s = static_cast<double>(d.window_samples) / options_.rate_hz;
  out_.valid = valid ? 1 : 0;
  const bool sent = params_out_.publish(out_);
  if (valid) {
    spdlog::info(
        "published params version {}{}: c1 {:.6g} m/V, c2 {:.6g}, c3 {:.6g}; held-out RMS {:.3g} m vs {:.3g} m in use; "
        "refit {:.1f} ms",
        out_.version, sent ? "" : " (PUBLISH FAILED)", out_.c1, out_.c2, out_.c3, d.holdout_rms_candidate_m,
        d.holdout_rms_in_use_m, d.duration_s * 1e3);
  }
}

void ReidentService::publish_model(const ModelDecision& d) {
  if (d.kind == ModelDecision::Kind::none) return;
  set_model(model_msg_, d.params);
  model_msg_.utime = wall_utime();
  model_msg_.version = d.version;
  const ModelScore* score = nullptr;
  for (const ModelScore& r : d.proposal.ranking) {
    if (r.kind == d.params.kind) score = &r;
  }
  model_msg_.residual_m = score != nullptr && std::isfinite(score->train_rms_m) ? score->train_rms_m : 0.0;
  model_msg_.heldout_rms_m =
      score != nullptr && std::isfinite(score->holdout_rms_m) ? score->holdout_rms_m : std::nan("");
  model_msg_.samples_used = static_cast<std::int64_t>(d.window_samples);
  model_msg_.window_s = static_cast<double>(d.window_samples) / options_.rate_hz;
  model_msg_.valid = true;
  const bool sent = model_out_.publish(model_msg_);
  spdlog::info("published {} {} version {}{} on the model channel: held-out RMS {:.3g} m vs {:.3g} m in use ({})",
               d.kind == ModelDecision::Kind::change ? "model change to" : "parameters of", to_string(d.params.kind),
               d.version, sent ? "" : " (PUBLISH FAILED)", model_msg_.heldout_rms_m, d.proposal.in_use_holdout_rms_m,
               d.proposal.reason);
}

void ReidentService::pin_model(const control_t& msg) {
  // MODE_OFF: the automatic choice again; a model's mode pins that model; anything else names none.
  const auto mode = feedforward_mode_from_wire(msg.mode);
  const std::optional<ModelKind> kind = mode ? model_kind_of(*mode) : std::nullopt;
  if (!kind && mode != FeedforwardMode::kOff) {
    spdlog::warn("pin-model request {}: mode {} names no model; ignored", msg.request_id, msg.mode);
    acks_.refused(msg.request_id, "mode " + std::to_string(msg.mode) + " names no model", wall_utime());
    return;
  }
  if (!chooser_->enabled()) {
    spdlog::warn("pin-model request {} refused: reidentifier.models is off, no model choice runs", msg.request_id);
    acks_.refused(msg.request_id,
                  "reidentifier.models is off: no model choice runs to pin (set reidentifier.models: auto, or a list "
                  "such as mem,pi, and restart the re-identifier)",
                  wall_utime());
    return;
  }
  acks_.acted(msg.request_id);
  chooser_->pin(kind);
  spdlog::info("model {} (request {})", kind ? "pinned to " + std::string(to_string(*kind)) : "choice automatic",
               msg.request_id);
}

void ReidentService::publish_status(std::int64_t now_us, bool stopping) {
  std::int8_t state = service_status_t::HEALTHY;
  std::string why;
  const double quiet_s = core_->seconds_since_sample(now_us);
  if (stopping) {
    state = service_status_t::STOPPING;
  } else if (core_->stale(now_us)) {
    state = service_status_t::DEGRADED;
    why = core_->seen_samples() ? fmt::format("no sample for {:.1f} s; ", quiet_s) : "no sample received yet; ";
  }
  if (!stopping && core_->poisoned()) {
    state = service_status_t::DEGRADED;
    why += fmt::format("last {} windows poisoned (NaN or dropout); ", core_->poisoned_streak());
  }
  const ParamsInUse& in_use = core_->in_use();
  const bool forged_recent = in_use.forged_sets() > 0 && now_us - forged_seen_us_ < kForgedDegradedUs;
  if (!stopping && (forged_recent || in_use.forged_applied())) {
    state = service_status_t::DEGRADED;
    why += fmt::format(
        "a set on HX_PARAMS carried our publisher id {:x} with version {}, which we never published "
        "(forged?): not used{}; {} such sets (params_forged); ",
        static_cast<std::uint64_t>(in_use.own_publisher_id()), in_use.last_forged_version(),
        in_use.forged_applied() ? ", but the compensator applies it" : "", in_use.forged_sets());
  }
  // Blocks without our axis since the last report: a bridge of fewer axes than this process
  // expects fits nothing here, which the poisoned-window rule would say only minutes later.
  const std::uint64_t wrong_axes = core_->counters().get(ReidentCounter::sensor_blocks_wrong_axes);
  if (!stopping && wrong_axes > wrong_axes_reported_) {
    state = service_status_t::DEGRADED;
    why += fmt::format("{} HX_SENSOR blocks without axis {} since the last report (sensor_blocks_wrong_axes); ",
                       wrong_axes - wrong_axes_reported_, axis_name(options_.axis));
  }
  wrong_axes_reported_ = wrong_axes;
  const LatencyStats& refit = core_->refit_time();
  if (options_.axis != 0) why += fmt::format("axis {}: ", axis_name(options_.axis));  // x: as before axes existed
  why += fmt::format("params version {} from '{}': c1 {:.6g} m/V, c2 {:.6g}, c3 {:.6g}", in_use.version(),
                     escape_wire(in_use.source()), in_use.params().c1, in_use.params().c2, in_use.params().c3);
  const std::int32_t applied = in_use.applied_version();
  if (applied != ParamsInUse::kUnknownVersion && applied != in_use.version()) {
    why += fmt::format("; the compensator applies version {}", applied);
  }
  if (refit.count() > 0) {
    why += fmt::format("; refit last {:.1f} ms, p50 {:.1f} ms, max {:.1f} ms", core_->last_refit_s() * 1e3,
                       refit.percentile(0.5) * 1e-6, static_cast<double>(refit.max_ns()) * 1e-6);
  }
  if (core_->held()) why += "; holding the set in use (hystloop-ctl hold off releases it)";
  if (const std::string note = acks_.refusal_note(wall_utime()); !note.empty()) why += "; " + note;
  if (chooser_->enabled()) {
    why += fmt::format("; model {}{}", to_string(chooser_->in_use().kind),
                       chooser_->pinned() ? fmt::format(" (pinned to {})", to_string(*chooser_->pinned())) : "");
  }
  status_.begin(state, std::move(why));
  reported_.report(status_, counter_entries());
  status_.counter("params_version", static_cast<std::uint64_t>(in_use.version()));
  status_.counter("params_held", core_->held() ? 1U : 0U);
  acks_.report(status_);
  if (applied != ParamsInUse::kUnknownVersion) {  // absent until a command at or before a sample is heard
    status_.counter("params_version_applied", static_cast<std::uint64_t>(applied));
  }
  if (refit.count() > 0) {
    status_.counter("refit_last_us", static_cast<std::uint64_t>(std::llround(core_->last_refit_s() * 1e6)));
    status_.counter("refit_p50_us", static_cast<std::uint64_t>(std::llround(refit.percentile(0.5) * 1e-3)));
    status_.counter("refit_max_us", static_cast<std::uint64_t>(refit.max_ns() / 1000));
  }
  reported_.report(status_, "sensor", sensor_->counters());
  reported_.report(status_, "command", command_->counters());
  reported_.report(status_, "params_in", params_in_->counters());
  reported_.report(status_, "control", control_->counters());
  reported_.report(status_, "trajectory", trajectory_->counters());
  reported_.report(status_, "scan", scan_->counters());
  reported_.report(status_, "params_out", params_out_.counters());
  reported_.report(status_, "model_out", model_out_.counters());
  status_.loop_timing(block_cost_);  // per-block handler cost
  block_cost_.reset();
  status_.publish(wall_utime());
}

void ReidentService::on_tick(std::int64_t /*wall_us*/) {
  const std::int64_t now = steady_us();
  publish_decision(core_->poll(now));
  publish_model(chooser_->poll(*core_, now));
  if (now >= next_status_us_) {
    publish_status(now, false);
    next_status_us_ += 1'000'000;
    if (next_status_us_ <= now) next_status_us_ = now + 1'000'000;
  } else if (acks_.due() && status_.immediate_allowed(monotonic_ns())) {
    publish_status(now, false);
  }
}

int ReidentService::run() {
  publish_status(steady_us(), false);  // announce ourselves at once (tests wait for it)
  next_status_us_ = steady_us() + 1'000'000;
  IoLoopOptions loop;
  loop.poll_timeout = std::chrono::microseconds(1000);
  loop.period = std::chrono::milliseconds(10);  // refit scheduling; status every 100th tick
  const int lcm_errors = run_io_loop(lcm_, loop, [this](std::int64_t wall_us) { on_tick(wall_us); });
  const std::int64_t now = steady_us();
  publish_status(now, true);
  const LatencyStats& refit = core_->refit_time();
  const ParamsInUse& in_use = core_->in_use();
  std::string counts;  // under their HX_STATUS names
  for (const auto& [name, value] : counter_entries()) counts += fmt::format(", {} {}", name, value);
  spdlog::info(
      "stopping: refit p50 {:.1f} ms max {:.1f} ms; params version {} c1 {:.6g} c2 {:.6g} c3 {:.6g} (compensator "
      "applied {}); {} LCM errors{}",
      refit.count() ? refit.percentile(0.5) * 1e-6 : 0.0, static_cast<double>(refit.max_ns()) * 1e-6, in_use.version(),
      in_use.params().c1, in_use.params().c2, in_use.params().c3,
      in_use.applied_version() == ParamsInUse::kUnknownVersion ? std::string("unknown")
                                                               : std::to_string(in_use.applied_version()),
      lcm_errors, counts);
  rig_check_->throw_if_refused();  // exit 2: started with a range the rig's bridge does not have
  return 0;
}

}  // namespace hystloop
