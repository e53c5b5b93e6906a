#include "ctl_link.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>

#include <spdlog/fmt/fmt.h>

#include "core/process.hpp"
#include "ctl_health.hpp"
#include "ctl_requests.hpp"
#include "ctl_verdict.hpp"
#include "ctl_watch.hpp"
#include "lcm/blocks.hpp"
#include "lcm/connection.hpp"
#include "lcm/subscription.hpp"
#include "lcm/url.hpp"
#include "runtime/status_reporter.hpp"

namespace hystloop::ctl {

namespace {

// A listening subcommand's queue on a block channel: a few seconds of blocks.
constexpr int kBlockQueue = 4'000;

}  // namespace

bool receive(CtlLink& link, Clock::time_point deadline, std::chrono::microseconds slice, int max_messages) {
  const auto left = std::chrono::duration_cast<std::chrono::microseconds>(deadline - Clock::now());
  return handle_pending(link.lcm(), std::clamp(left, std::chrono::microseconds(0), slice), max_messages) >= 0;
}

int receive_failed(const CtlLink& link) {
  std::fprintf(stderr, "hystloop-ctl: LCM receive failed on %s\n", link.url().c_str());
  return 1;
}

Clock::time_point after(double seconds) {
  return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

CtlLink::CtlLink(const LinkOptions& options)
    : channels_(options.rig),
      url_(resolve_lcm_url_for_10khz(options.lcm_url, options.allow_network)),
      lcm_(open_lcm(url_, options.allow_network)) {}

int run_status(CtlLink& link, const StatusOptions& o) {
  StatusBoard board;
  Subscription<service_status_t> sub(link.lcm(), link.channels().status,
                                     [&](const service_status_t& s, std::int64_t) { board.update(s); });
  const bool waiting = !o.wait_healthy.empty();
  const auto deadline = after(waiting ? o.timeout_s : o.listen_s);
  HealthVerdict verdict;
  while (Clock::now() < deadline) {
    if (!receive(link, deadline, std::chrono::microseconds(100'000))) return receive_failed(link);
    if (waiting) {
      verdict = check_health(board, o.wait_healthy, o.accept_safe, o.accept_degraded);
      if (verdict.healthy) break;
    }
  }
  for (const auto& [name, report] : board.processes())
    std::printf("%s\n", format_status(report, o.all_counters).c_str());
  std::fflush(stdout);
  if (waiting) {
    verdict = check_health(board, o.wait_healthy, o.accept_safe, o.accept_degraded);
    if (verdict.healthy) return 0;
    std::fprintf(stderr, "hystloop-ctl: not healthy after %g s on %s: %s\n", o.timeout_s,
                 link.channels().status.c_str(), fmt::format("{}", fmt::join(verdict.problems, "; ")).c_str());
    return 1;
  }
  if (board.processes().empty()) {
    std::fprintf(stderr, "hystloop-ctl: no status on %s within %g s (is the rig running, on %s?)\n",
                 link.channels().status.c_str(), o.listen_s, link.url().c_str());
    return 1;
  }
  return 0;
}

int run_watch(CtlLink& link, const WatchOptions& o) {
  install_stop_handlers();
  WatchLine line;
  std::optional<std::int64_t> late_before_report;
  const auto axis = static_cast<std::size_t>(o.axis);
  TruthPairing truth(axis);
  Subscription<sensor_block_t> samples(link.lcm(), link.channels().sensor,
                                       [&](const sensor_block_t& b, std::int64_t) {
                                         line.second.add_sensor_block(b, axis);
                                         truth.add_sensor_block(b, line.second);
                                       },
                                       {.queue_capacity = kBlockQueue, .on_reject = {}});
  Subscription<sim_truth_t> truths(link.lcm(), link.channels().sim_truth,
                                   [&](const sim_truth_t& t, std::int64_t) { truth.add_truth_block(t, line.second); },
                                   {.queue_capacity = kBlockQueue, .on_reject = {}});
  Subscription<command_block_t> commands(
      link.lcm(), link.channels().command,
      [&](const command_block_t& c, std::int64_t) {
        if (axis >= axes_of(c)) return;
        line.second.commands += static_cast<std::uint64_t>(c.n_ticks);
        line.params_in_use = command_tick(c, static_cast<std::size_t>(c.n_ticks - 1), axis).params_version;
      },
      {.queue_capacity = kBlockQueue, .on_reject = {}});
  Subscription<mem_params_t> params(link.lcm(), link.channels().params, [&](const mem_params_t& p, std::int64_t) {
    if (p.valid && static_cast<std::size_t>(p.axis) == axis)
      line.params_latest = std::max(line.params_latest.value_or(0), p.version);
  });
  Subscription<service_status_t> status(
      link.lcm(), link.channels().status, [&](const service_status_t& s, std::int64_t) {
        if (s.process == o.compensator_process) {
          line.learning_rms_nm = learning_rms_nm(s, static_cast<int>(axis));
          line.learning_periods = find_counter(s, axis_counter("learning_periods", static_cast<int>(axis)));
          line.trajectories_refused = find_counter(s, "trajectory_refused");
          line.trajectories_shaped = find_counter(s, "trajectories_shaped");
        }
        if (s.process != o.bridge_process) return;
        line.late_delta = s.late - late_before_report.value_or(s.late);
        late_before_report = s.late;
        line.late_total = s.late;
        line.bridge_state = state_name(s.state);
        line.clamped_per_s = find_counter(s, "clamped_per_s");
      });

  const auto start = Clock::now();
  auto next_print = start + std::chrono::seconds(1);
  const auto end = o.seconds > 0 ? after(o.seconds) : Clock::time_point::max();
  while (!stop_requested()) {
    const auto wake = std::min(next_print, end);
    if (!receive(link, wake, std::chrono::microseconds(50'000), 1024)) return receive_failed(link);
    const auto now = Clock::now();
    if (now >= next_print) {
      line.elapsed_s = std::chrono::duration<double>(next_print - start).count();
      std::printf("%s\n", format_watch_line(line).c_str());
      std::fflush(stdout);
      line.second = {};
      line.late_delta.reset();
      next_print += std::chrono::seconds(1);
    }
    if (now >= end) break;
  }
  return 0;
}

namespace {

// Publishes with `publish` (3 copies) on `channel`, prints "sent <what> <description> ..." and, with
// wait, follows the compensator's HX_STATUS until it reports on `version`. Says nothing: the
// caller reports the result.
template <class Message>
VerdictResult publish_and_follow(CtlLink& link, const std::string& channel, const Message& msg, const char* what,
                                 const VerdictOptions& o) {
  VerdictResult r;
  // Listening before publishing: the compensator reports right after it decides.
  bool heard = false, has_counters = false;
  Subscription<service_status_t> status(link.lcm(), link.channels().status,
                                        [&](const service_status_t& s, std::int64_t) {
                                          if (s.process != o.compensator_process) return;
                                          heard = true;
                                          const TrajectoryVerdict v = trajectory_verdict(s, msg.version);
                                          has_counters = has_counters || v.has_counters;
                                          if (r.verdict.outcome == TrajectoryOutcome::kPending) r.verdict = v;
                                        });
  if (!publish_repeated(link.lcm(), channel, msg)) {
    r.error = "could not publish on " + channel;
    return r;
  }
  r.published = true;
  if (!o.wait) return r;
  const auto deadline = after(o.timeout_s);
  while (r.verdict.outcome == TrajectoryOutcome::kPending && Clock::now() < deadline) {
    if (!receive(link, deadline, std::chrono::microseconds(50'000))) {
      r.error = "LCM failed while waiting for the verdict (" + link.url() + ")";
      return r;
    }
  }
  const long long version = static_cast<long long>(msg.version);
  const std::string& who = o.compensator_process;
  switch (r.verdict.outcome) {
    case TrajectoryOutcome::kAccepted:
    case TrajectoryOutcome::kShaped: return r;
    case TrajectoryOutcome::kRefused:
      r.error = fmt::format("{} refused {} {}: {}", who, what, version,
                            r.verdict.detail.empty() ? "(no reason given)" : r.verdict.detail);
      return r;
    case TrajectoryOutcome::kSuperseded:
      r.error = fmt::format("{} decided on trajectory {}, sent after {}, before reporting on it (another sender?)", who,
                            static_cast<long long>(r.verdict.later_version), version);
      return r;
    case TrajectoryOutcome::kPending: break;
  }
  const std::string hint =
      !heard ? " (no status from '" + o.compensator_process + "' on " + link.channels().status + ": is it running?)"
      : !has_counters ? " ('" + o.compensator_process + "' reports no trajectory_version: a build without verdicts?)"
                      : "";
  r.error = fmt::format("no compensator confirmed {} version {} within {:g} s{}", what, version, o.timeout_s, hint);
  return r;
}

// The tool's lines for a result of publish_and_follow; its exit status.
template <class Message>
int print_verdict(const VerdictResult& r, const std::string& channel, const Message& msg, const char* what,
                  const std::string& description, const VerdictOptions& o) {
  if (r.published) {
    std::printf("hystloop-ctl: sent %s %s on %s (version %lld)\n", what, description.c_str(), channel.c_str(),
                static_cast<long long>(msg.version));
    std::fflush(stdout);
  }
  if (!r.error.empty()) {
    std::fprintf(stderr, "hystloop-ctl: %s\n", r.error.c_str());
    return 1;
  }
  if (!o.wait) return 0;
  const long long version = static_cast<long long>(msg.version);
  const char* who = o.compensator_process.c_str();
  if (r.verdict.outcome == TrajectoryOutcome::kShaped) {
    std::printf("hystloop-ctl: %s shaped %s %lld: %s\n", who, what, version,
                r.verdict.detail.empty() ? "(no detail given)" : r.verdict.detail.c_str());
  } else {
    std::printf("hystloop-ctl: %s accepted %s %lld%s%s\n", who, what, version, r.verdict.detail.empty() ? "" : ": ",
                r.verdict.detail.c_str());
  }
  return 0;
}

}  // namespace

VerdictResult send_trajectory(CtlLink& link, const trajectory_t& msg, const VerdictOptions& o) {
  return publish_and_follow(link, link.channels().trajectory, msg, "trajectory", o);
}

VerdictResult send_scan(CtlLink& link, const scan_t& msg, const VerdictOptions& o) {
  return publish_and_follow(link, link.channels().scan, msg, "scan", o);
}

int publish_trajectory(CtlLink& link, const trajectory_t& msg, const std::string& description,
                       const VerdictOptions& o) {
  return print_verdict(send_trajectory(link, msg, o), link.channels().trajectory, msg, "trajectory", description, o);
}

int publish_scan(CtlLink& link, const scan_t& msg, const std::string& description, const VerdictOptions& o) {
  return print_verdict(send_scan(link, msg, o), link.channels().scan, msg, "scan", description, o);
}

ControlResult request_control(CtlLink& link, const control_t& msg, const std::string& what, const AckOptions& o) {
  ControlResult r;
  // Listening before publishing: a process answers right after it acts.
  AckTracker tracker(msg.request_id, o.expected, o.state);
  Subscription<service_status_t> status(link.lcm(), link.channels().status,
                                        [&](const service_status_t& s, std::int64_t) {
                                          tracker.update(s);
                                          r.heard[s.process] = s;
                                        });
  if (!publish_repeated(link.lcm(), link.channels().control, msg)) {
    r.error = "could not publish on " + link.channels().control;
    return r;
  }
  r.published = true;
  if (!o.wait) {
    r.confirmed = true;
    return r;
  }
  const auto start = Clock::now();
  const auto deadline = after(o.timeout_s);
  const auto gathered = after(std::min(o.gather_s, o.timeout_s));
  while (Clock::now() < deadline && !tracker.finished(Clock::now() >= gathered)) {
    if (!receive(link, deadline, std::chrono::microseconds(20'000))) {
      r.error = "LCM failed while waiting for the answers (" + link.url() + ")";
      return r;
    }
  }
  r.waited_s = std::chrono::duration<double>(Clock::now() - start).count();
  if (r.heard.empty()) {
    r.error = fmt::format("no rig is running: nothing reported on {} within {:g} s ({} not confirmed)",
                          link.channels().status, o.timeout_s, what);
    return r;
  }
  r.confirmed = tracker.all_confirmed(true);
  r.answers = describe_answers(tracker, true);
  if (!r.confirmed) {
    r.error = fmt::format("{} not confirmed (waited {:.1f} s of --timeout {:g} s)", what, r.waited_s, o.timeout_s);
  }
  return r;
}

int send_control_confirmed(CtlLink& link, const control_t& msg, const std::string& what, const AckOptions& o,
                           std::map<std::string, service_status_t>* last) {
  const ControlResult r = request_control(link, msg, what, o);
  if (r.published) {
    const std::string to_whom = msg.target.empty() ? "every process" : "'" + msg.target + "'";
    std::printf("hystloop-ctl: sent %s to %s on %s (request %lld)\n", what.c_str(), to_whom.c_str(),
                link.channels().control.c_str(), static_cast<long long>(msg.request_id));
    std::fflush(stdout);
  }
  if (last != nullptr) *last = r.heard;
  for (const std::string& line : r.answers)
    std::fprintf(r.confirmed ? stdout : stderr, "hystloop-ctl: %s\n", line.c_str());
  if (!r.error.empty()) {
    std::fprintf(stderr, "hystloop-ctl: %s\n", r.error.c_str());
    return 1;
  }
  if (o.wait) std::printf("hystloop-ctl: %s confirmed in %.0f ms\n", what.c_str(), r.waited_s * 1e3);
  return 0;
}

StatusWait wait_for_status(CtlLink& link, const std::string& process, const StateCheck& until, double timeout_s) {
  StatusWait w;
  Subscription<service_status_t> status(link.lcm(), link.channels().status,
                                        [&](const service_status_t& s, std::int64_t) {
                                          w.last[s.process] = s;
                                          if (s.process == process && until(s)) w.satisfied = true;
                                        });
  const auto deadline = after(timeout_s);
  while (!w.satisfied && Clock::now() < deadline) {
    if (!receive(link, deadline, std::chrono::microseconds(20'000))) break;
  }
  return w;
}

int run_series(CtlLink& link, const std::vector<SeriesStep>& steps, const SeriesRunOptions& o) {
  install_stop_handlers();
  SeriesTracker tracker(steps, o.dt_s);
  const double total_s = series_duration_s(steps);
  std::optional<std::int8_t> mode;  // of the latest command
  std::optional<std::int64_t> last_seq;
  bool sent = false;
  const auto axis = static_cast<std::size_t>(o.axis);
  auto on_command = [&](const command_block_t& c, std::int64_t) {
    if (axis >= axes_of(c)) return;  // a stage without that axis: the compensator refuses the requests
    for_each_tick(
        c,
        [&](const CommandTick& t) {
          mode = t.mode;
          last_seq = t.seq;
          if (!sent || !o.wait) return;
          if (const auto step = tracker.on_command(t.seq, t.mode == command_block_t::MODE_EXPERIMENT)) {
            std::printf("[%zu/%zu] %s\n", *step + 1, steps.size(), steps[*step].what.c_str());
            std::fflush(stdout);
          }
        },
        axis);
  };
  Subscription<command_block_t> commands(link.lcm(), link.channels().command, on_command,
                                         {.queue_capacity = kBlockQueue, .on_reject = {}});
  // The plan runs a horizon ahead of the stage: the series is done when the sample of its last
  // tick has arrived, not when that tick was planned.
  std::int64_t last_sample = -1;
  Subscription<sensor_block_t> samples(link.lcm(), link.channels().sensor,
                                       [&](const sensor_block_t& b, std::int64_t) {
                                         if (b.n_ticks > 0)
                                           last_sample = std::max<std::int64_t>(last_sample, b.seq + b.n_ticks - 1);
                                       },
                                       {.queue_capacity = kBlockQueue, .on_reject = {}});
  auto pump = [&](Clock::time_point until_time) {
    return receive(link, until_time, std::chrono::microseconds(50'000), 4096);
  };

  // Commands must flow, and no experiment may be running: ours would queue behind it.
  const auto listen_end = after(1.0);
  while (!mode && Clock::now() < listen_end && !stop_requested()) {
    if (!pump(listen_end)) return 1;
  }
  if (!mode) {
    std::fprintf(stderr,
                 "hystloop-ctl: no command on %s within 1 s: is the compensator running and the bridge "
                 "sending samples? (hystloop-ctl status)\n",
                 link.channels().command.c_str());
    return 1;
  }
  if (*mode == command_block_t::MODE_EXPERIMENT) {
    std::fprintf(stderr,
                 "hystloop-ctl: an experiment is running: wait for it to end, or hystloop-ctl stop-experiment\n");
    return 1;
  }

  const std::int64_t base_id = new_request_id(wall_utime(), static_cast<int>(::getpid()));
  auto send_stop = [&] {
    publish_repeated(link.lcm(), link.channels().control,
                     make_control(control_t::STOP_EXPERIMENT, o.target, base_id + 100'000, wall_utime()));
  };
  std::printf("hystloop-ctl: sending %zu experiment requests on %s (%.1f s back to back)\n", steps.size(),
              link.channels().control.c_str(), total_s);
  std::fflush(stdout);
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const std::int64_t now = wall_utime();
    control_t msg = make_control(control_t::START_EXPERIMENT, o.target, base_id + static_cast<std::int64_t>(i), now);
    msg.axis = static_cast<std::int8_t>(o.axis);
    apply(steps[i].request, msg);
    if (!publish_repeated(link.lcm(), link.channels().control, msg)) {
      std::fprintf(stderr, "hystloop-ctl: could not publish request %zu on %s%s\n", i + 1,
                   link.channels().control.c_str(), i > 0 ? ": sending STOP_EXPERIMENT" : "");
      if (i > 0) send_stop();
      return 1;
    }
    sent = true;
    if (!pump(Clock::now())) return 1;  // keep the command queue short while sending
  }
  if (!o.wait) {
    std::printf("hystloop-ctl: sent %zu experiment requests on %s (%.1f s back to back)\n", steps.size(),
                link.channels().control.c_str(), total_s);
    return 0;
  }

  const auto start_deadline = after(o.start_timeout_s);
  const auto end_deadline = after(total_s + o.start_timeout_s + 5.0);
  while (!tracker.finished() && !tracker.ended_early() && !stop_requested()) {
    const auto deadline = tracker.started() ? end_deadline : start_deadline;
    if (Clock::now() >= deadline) break;
    if (!pump(deadline)) return receive_failed(link);
  }
  if (stop_requested()) {
    send_stop();
    std::fprintf(stderr, "hystloop-ctl: interrupted: sent STOP_EXPERIMENT (the queued experiments are dropped)\n");
    return 1;
  }
  if (!tracker.started()) {
    std::fprintf(stderr,
                 "hystloop-ctl: no experiment command within %g s of the requests: the compensator refused "
                 "them or did not get them (see its log; hystloop-ctl status)\n",
                 o.start_timeout_s);
    return 1;
  }
  if (tracker.ended_early()) {
    std::fprintf(stderr,
                 "hystloop-ctl: the series ended at tick %lld, before its end at tick %lld: stopped, or the "
                 "compensator restarted\n",
                 static_cast<long long>(last_seq.value_or(0)), static_cast<long long>(tracker.end_tick()));
    return 1;
  }
  if (!tracker.finished()) {
    std::fprintf(stderr, "hystloop-ctl: the series did not end within %.1f s (commands stopped arriving?)\n",
                 total_s + o.start_timeout_s + 5.0);
    return 1;
  }
  const auto measured_deadline = after(2.0);
  while (last_sample < tracker.end_tick() && Clock::now() < measured_deadline && !stop_requested()) {
    if (!pump(measured_deadline)) return 1;
  }
  if (last_sample < tracker.end_tick()) {
    std::fprintf(stderr,
                 "hystloop-ctl: the series' last tick %lld was planned but its sample did not arrive within 2 s "
                 "(last sample %lld on %s: is the bridge running?)\n",
                 static_cast<long long>(tracker.end_tick()), static_cast<long long>(last_sample),
                 link.channels().sensor.c_str());
    return 1;
  }
  std::printf("hystloop-ctl: series done: %zu steps, ticks %lld .. %lld (%.1f s), measured\n", steps.size(),
              static_cast<long long>(tracker.first_tick().value_or(0)), static_cast<long long>(tracker.end_tick()),
              total_s);
  return 0;
}

std::int32_t next_params_version(CtlLink& link, double listen_s) {
  std::int32_t highest = 0;
  Subscription<mem_params_t> params(link.lcm(), link.channels().params, [&](const mem_params_t& p, std::int64_t) {
    highest = std::max(highest, p.version);
  });
  Subscription<command_block_t> commands(
      link.lcm(), link.channels().command,
      [&](const command_block_t& c, std::int64_t) {
        for_each_tick(c, [&](const CommandTick& t) { highest = std::max(highest, t.params_version); });
      },
      {.queue_capacity = kBlockQueue, .on_reject = {}});
  const auto deadline = after(listen_s);
  while (Clock::now() < deadline) {
    if (!receive(link, deadline, std::chrono::microseconds(50'000), 1024)) break;
  }
  // Saturating: after a forged 2147483647 the set still goes out (as a new publisher it is taken anyway).
  return highest < std::numeric_limits<std::int32_t>::max() ? highest + 1 : highest;
}

}  // namespace hystloop::ctl
