#include "ctl_link.hpp"

#include <algorithm>
#include <cstdio>
#include <string>

#include "core/process.hpp"
#include "ctl_health.hpp"
#include "ctl_watch.hpp"
#include "lcm/connection.hpp"
#include "lcm/subscription.hpp"
#include "lcm/url.hpp"

namespace hystloop::ctl {

namespace {

using Clock = std::chrono::steady_clock;

std::chrono::microseconds until(Clock::time_point deadline) {
  return std::max(std::chrono::microseconds(0),
                  std::chrono::duration_cast<std::chrono::microseconds>(deadline - Clock::now()));
}

Clock::time_point after(double seconds) {
  return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

std::string resolved_url(const LinkOptions& o) {
  std::string url = resolve_lcm_url_for_10khz(o.lcm_url, o.allow_network);
  return url;
}

}  // namespace

CtlLink::CtlLink(const LinkOptions& options)
    : channels_(options.rig), url_(resolved_url(options)), lcm_(open_lcm(url_, options.allow_network)) {}

int run_status(CtlLink& link, const StatusOptions& o) {
  StatusBoard board;
  Subscription<service_status_t> sub(link.lcm(), link.channels().status,
                                     [&](const service_status_t& s, std::int64_t t) { board.update(s, t); });
  const bool waiting = !o.wait_healthy.empty();
  const auto deadline = after(waiting ? o.timeout_s : o.listen_s);
  HealthVerdict verdict;
  while (Clock::now() < deadline) {
    if (handle_pending(link.lcm(), std::min(until(deadline), std::chrono::microseconds(100'000))) < 0) {
      std::fprintf(stderr, "hystloop-ctl: LCM receive failed on %s\n", link.url().c_str());
      return 1;
    }
    if (waiting) {
      verdict = check_health(board, o.wait_healthy, o.accept_safe, o.accept_degraded);
      if (verdict.healthy) break;
    }
  }
  for (const auto& [name, report] : board.processes()) std::printf("%s\n", format_status(report, o.all_counters).c_str());
  std::fflush(stdout);
  if (waiting) {
    verdict = check_health(board, o.wait_healthy, o.accept_safe, o.accept_degraded);
    if (verdict.healthy) return 0;
    std::string problems;
    for (const auto& p : verdict.problems) {
      if (!problems.empty()) problems += "; ";
      problems += p;
    }
    std::fprintf(stderr, "hystloop-ctl: not healthy after %g s on %s: %s\n", o.timeout_s,
                 link.channels().status.c_str(), problems.c_str());
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
  TickMatcher matcher;
  WatchLine line;
  std::optional<std::int64_t> late_before_report;
  Subscription<sensor_sample_t>::Options fast;
  fast.queue_capacity = 20'000;
  Subscription<sensor_sample_t> samples(
      link.lcm(), link.channels().sensor,
      [&](const sensor_sample_t& s, std::int64_t) {
        ++line.second.samples;
        if (const auto e = matcher.on_sample(s.seq, s.y_m)) line.second.add_error(*e);
      },
      fast);
  Subscription<actuator_command_t>::Options fast_commands;
  fast_commands.queue_capacity = 20'000;
  Subscription<actuator_command_t> commands(
      link.lcm(), link.channels().command,
      [&](const actuator_command_t& c, std::int64_t) {
        ++line.second.commands;
        line.params_in_use = c.params_version;
        if (const auto e = matcher.on_command(c.seq, c.y_ref_m)) line.second.add_error(*e);
      },
      fast_commands);
  Subscription<mem_params_t> params(link.lcm(), link.channels().params,
                                    [&](const mem_params_t& p, std::int64_t) {
                                      if (p.valid) line.params_latest = std::max(line.params_latest.value_or(0), p.version);
                                    });
  Subscription<service_status_t> status(link.lcm(), link.channels().status,
                                        [&](const service_status_t& s, std::int64_t) {
                                          if (s.process != o.bridge_process) return;
                                          line.late_delta = s.late - late_before_report.value_or(s.late);
                                          late_before_report = s.late;
                                          line.late_total = s.late;
                                          line.latency_p99_us = s.latency_p99_us;
                                          line.bridge_state = state_name(s.state);
                                        });

  const auto start = Clock::now();
  auto next_print = start + std::chrono::seconds(1);
  const auto end = o.seconds > 0 ? after(o.seconds) : Clock::time_point::max();
  while (!stop_requested()) {
    const auto wake = std::min(next_print, end);
    if (handle_pending(link.lcm(), std::min(until(wake), std::chrono::microseconds(50'000)), 1024) < 0) {
      std::fprintf(stderr, "hystloop-ctl: LCM receive failed on %s\n", link.url().c_str());
      return 1;
    }
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

std::int32_t next_params_version(CtlLink& link, double listen_s) {
  std::int32_t highest = 0;
  Subscription<mem_params_t> params(link.lcm(), link.channels().params,
                                    [&](const mem_params_t& p, std::int64_t) { highest = std::max(highest, p.version); });
  Subscription<actuator_command_t>::Options fast;
  fast.queue_capacity = 20'000;
  Subscription<actuator_command_t> commands(
      link.lcm(), link.channels().command,
      [&](const actuator_command_t& c, std::int64_t) { highest = std::max(highest, c.params_version); }, fast);
  const auto deadline = after(listen_s);
  while (Clock::now() < deadline) {
    if (handle_pending(link.lcm(), std::min(until(deadline), std::chrono::microseconds(50'000)), 1024) < 0) break;
  }
  return highest + 1;
}

}  // namespace hystloop::ctl
