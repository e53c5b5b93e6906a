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
#include "loop/bridge_core.hpp"  // sample_flags
#include "models/model_descriptors.hpp"
#include "runtime/io_loop.hpp"

namespace hystloop {

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
      rig_check_(lcm, channels.status, settings.rig_limits, "compensator"),
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
          law.observe({t.seq, t.u_V, t.y_m, t.u_ff_V, (t.flags & sample_flags::kSafeState) != 0});
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
        apply_trajectory(spec, pending_start_utime_, pending_version_, pending_axis_, false);
      } catch (const std::exception& e) {
        ++counters_.trajectory_refused;
        decide_trajectory(pending_version_, e.what(), true, false);
      }
      report_if_due();
    }
  }
  take_checked_trajectories();
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
  ++law_epoch_;
  ++counters_.bridge_restarts;
}

int CompensatorService::run() {
  for (const std::string& line : describe(settings_)) spdlog::info("{}", line);
  spdlog::info("channels: {} in, {} out; {}, {}, {}, {}, {} in", samples_.channel(), command_pub_.channel(),
               trajectories_.channel(), scans_.channel(), params_.channel(), models_.channel(), control_.channel());
  const double started_s = monotonic_s();
  IoLoopOptions options;
  options.poll_timeout = std::chrono::microseconds(20000);
  // Ticks of StatusReporter's immediate interval, so that a report a verdict asked for while
  // the interval had not passed goes out when it has; every tenth is the periodic report.
  options.period = std::chrono::milliseconds(StatusReporter::kMinImmediateInterval_ns / 1'000'000);
  constexpr int kTicksPerReport = 1'000'000'000 / StatusReporter::kMinImmediateInterval_ns;
  int ticks = 0;
  const int errors = run_io_loop(lcm_, options, [&](std::int64_t utime) {
    take_checked_trajectories();  // a check that ended while no sensor block came
    if (++ticks < kTicksPerReport) return void(report_if_due());
    ticks = 0;
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
  rig_check_.throw_if_refused();  // exit 2: started with limits the rig's bridge does not have
  return errors > 0 ? 1 : 0;
}

}  // namespace hystloop
