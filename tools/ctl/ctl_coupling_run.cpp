// hystloop-ctl experiment coupling's I/O (ctl_coupling.hpp): the servo off, each axis excited in
// turn through the compensator, every axis's sensor recorded, the gains put back.
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <optional>
#include <utility>

#include <spdlog/fmt/fmt.h>

#include "core/clock.hpp"
#include "core/process.hpp"
#include "ctl_coupling.hpp"
#include "ctl_requests.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/servo_gains_status.hpp"
#include "lcm/status_counters.hpp"
#include "lcm/subscription.hpp"
#include "models/axis_coupling.hpp"
#include "runtime/status_reporter.hpp"

namespace hystloop::ctl {

namespace {

// SET_GAINS of kp, ki, kd on `axis` (-1: every axis; the notch stays as in force), confirmed by the bridge.
int set_servo(CtlLink& link, const CouplingRunOptions& o, int axis, double kp, double ki, double kd) {
  GainsRequest g;
  g.axis = axis;
  g.kp = kp;
  g.ki = ki;
  g.kd = kd;
  const std::int64_t now = wall_utime();
  control_t msg = make_control(control_t::SET_GAINS, o.bridge_process, new_request_id(now, ::getpid()), now);
  apply(g, msg);
  AckOptions ack;
  ack.timeout_s = o.timeout_s;
  ack.expected = {o.bridge_process};
  return send_control_confirmed(link, msg, "SET_GAINS", ack);
}

}  // namespace

int run_coupling_experiment(CtlLink& link, const CouplingRunOptions& o) {
  o.validate();
  install_stop_handlers();
  // The stage's axes from its sensor blocks; while an axis is excited, every axis's sensor at its
  // experiment's ticks.
  int axes = 0;
  int moved = -1;
  std::vector<CouplingRecord> records;
  Clock::time_point last_sample{};
  Subscription<sensor_block_t>::Options queue;
  queue.queue_capacity = 4000;
  Subscription<sensor_block_t> sensor(
      link.lcm(), link.channels().sensor,
      [&](const sensor_block_t& b, std::int64_t) {
        axes = static_cast<int>(axes_of(b));
        if (moved < 0 || moved >= axes || records.empty()) return;
        CouplingRecord& r = records.back();
        for (std::size_t i = 0, n = ticks_of(b); i < n; ++i) {
          const SensorTick t = sensor_tick(b, i, static_cast<std::size_t>(moved));
          if (!std::isnan(t.y_ref_m) || t.u_V == 0.0) continue;  // not the experiment's tick
          for (int j = 0; j < axes; ++j) {
            r.y_m[static_cast<std::size_t>(j)].push_back(sensor_tick(b, i, static_cast<std::size_t>(j)).y_m);
          }
          last_sample = Clock::now();
        }
      },
      queue);

  const StatusWait w = wait_for_status(
      link, o.bridge_process, [](const service_status_t&) { return true; }, o.timeout_s);
  const auto bridge = w.last.find(o.bridge_process);
  // Each axis's gains, to put back (a one-axis bridge reports x's only).
  std::array<std::optional<ServoGainsFigures>, kMaxAxes> axis_gains{};
  if (bridge != w.last.end()) {
    for (int a = 0; a < kMaxAxes; ++a) {
      axis_gains[static_cast<std::size_t>(a)] =
          servo_gains_from_counters([&](std::string_view name) { return find_counter(bridge->second, name); }, a);
    }
  }
  const std::optional<ServoGainsFigures>& gains = axis_gains[0];
  if (!gains) {
    std::fprintf(stderr, "hystloop-ctl: no servo gains from '%s' on %s within %g s: is a rig running?\n",
                 o.bridge_process.c_str(), link.channels().status.c_str(), o.timeout_s);
    return 1;
  }
  const auto deadline = after(o.timeout_s);
  while (axes == 0 && Clock::now() < deadline) {
    if (!receive(link, deadline, std::chrono::microseconds(50'000))) return receive_failed(link);
  }
  if (axes < 2) {
    std::fprintf(stderr, "hystloop-ctl: %s\n",
                 axes == 0 ? "no sensor blocks: is the bridge running?"
                           : "the stage has one axis: there is no coupling to identify");
    return 1;
  }
  std::printf(
      "hystloop-ctl: coupling of %d axes: each axis in turn a %g V, %g Hz sine for %g s, the servo off (kp %g, ki %g, "
      "kd %g put back after)\n",
      axes, o.amplitude_V, o.frequency_Hz, o.duration_s, gains->kp, gains->ki_per_s, gains->kd_s);
  std::fflush(stdout);
  // From the first SET_GAINS on, every way out puts the gains back (an unanswered request may still
  // have zeroed them) and stops an excitation still running.
  bool restored = false;
  const auto restore = [&]() -> bool {
    if (moved >= 0) {
      const std::int64_t now = wall_utime();
      AckOptions ack;
      ack.timeout_s = o.timeout_s;
      ack.expected = {o.compensator_process};
      send_control_confirmed(
          link, make_control(control_t::STOP_EXPERIMENT, o.compensator_process, new_request_id(now, ::getpid()), now),
          "STOP_EXPERIMENT", ack);
      moved = -1;
    }
    restored = true;
    for (int a = 0; a < axes; ++a) {
      // An axis the bridge reported no gains of has x's (a bridge that does not report per axis).
      const ServoGainsFigures& g = axis_gains[static_cast<std::size_t>(a)].value_or(*gains);
      restored = set_servo(link, o, axes > 1 ? a : -1, g.kp, g.ki_per_s, g.kd_s) == 0 && restored;
    }
    return restored;
  };
  struct OnExit {
    std::function<void()> fn;
    explicit OnExit(std::function<void()> f) : fn(std::move(f)) {}
    OnExit(const OnExit&) = delete;
    OnExit& operator=(const OnExit&) = delete;
    ~OnExit() {
      try {
        fn();
      } catch (...) {  // already leaving on an error: the message below names the gains
      }
    }
  } on_exit([&] {
    if (!restored && !restore()) {
      std::fprintf(stderr, "hystloop-ctl: the servo's gains were NOT confirmed back: set them with\n");
      for (int a = 0; a < std::max(axes, 1); ++a) {
        const ServoGainsFigures& g = axis_gains[static_cast<std::size_t>(a)].value_or(*gains);
        std::fprintf(stderr, "  hystloop-ctl gains%s --kp %g --ki %g --kd %g\n",
                     axes > 1 ? (" --axis " + std::string(axis_name(a))).c_str() : "", g.kp, g.ki_per_s, g.kd_s);
      }
    }
  });
  if (set_servo(link, o, -1, 0.0, 0.0, 0.0) != 0) return 1;

  // One axis's experiment: 0 done, else the exit status.
  const auto excite = [&](int a) -> int {
    const ExperimentRequest e = coupling_experiment(o);
    const std::int64_t now = wall_utime();
    control_t msg =
        make_control(control_t::START_EXPERIMENT, o.compensator_process, new_request_id(now, ::getpid()), now);
    apply(e, msg);
    msg.axis = static_cast<std::int8_t>(a);
    records.push_back({a, {}});
    moved = a;
    AckOptions ack;
    ack.timeout_s = o.timeout_s;
    ack.expected = {o.compensator_process};
    if (send_control_confirmed(link, msg, fmt::format("START_EXPERIMENT on {}", axis_name(a)), ack) != 0) return 1;
    // Its ticks start a horizon ahead and last the duration; done once none came for 0.2 s.
    const auto end = after(o.duration_s + o.timeout_s);
    while (Clock::now() < end && !stop_requested()) {
      if (!receive(link, end, std::chrono::microseconds(20'000))) return receive_failed(link);
      if (!records.back().y_m[0].empty() && Clock::now() - last_sample > std::chrono::milliseconds(200)) break;
    }
    if (stop_requested()) return 1;  // still moving: on_exit stops it
    moved = -1;
    std::printf("hystloop-ctl: %s excited: %zu samples\n", std::string(axis_name(a)).c_str(),
                records.back().y_m[0].size());
    std::fflush(stdout);
    const auto rest = after(o.rest_s);  // the axis comes back to its reference before the next moves
    while (Clock::now() < rest && !stop_requested()) {
      if (!receive(link, rest, std::chrono::microseconds(20'000))) return receive_failed(link);
    }
    return 0;
  };
  int rc = 0;
  for (int a = 0; a < axes && rc == 0 && !stop_requested(); ++a) rc = excite(a);
  if (!restore()) {
    std::fprintf(stderr,
                 "hystloop-ctl: the servo's gains were NOT confirmed back: set them with hystloop-ctl gains "
                 "--kp %g --ki %g --kd %g\n",
                 gains->kp, gains->ki_per_s, gains->kd_s);
    restored = true;  // said once
    rc = 1;
  }
  if (stop_requested()) {
    std::fprintf(stderr, "hystloop-ctl: stopped before every axis was excited\n");
    return 1;
  }
  if (rc != 0) return rc;

  const CouplingFitResult fit = fit_records(records, axes);
  if (fit.status != FitStatus::ok) {
    std::fprintf(stderr, "hystloop-ctl: the coupling fit was refused: %s\n%s", fit.reason.c_str(),
                 describe_fit(fit, axes).c_str());
    return 1;
  }
  std::printf("hystloop-ctl: coupling identified (C(to, from), standard errors):\n%s", describe_fit(fit, axes).c_str());
  if (!o.out.empty()) {
    std::ofstream out(o.out);
    out << decoupling_yaml(fit, axes, "hystloop-ctl experiment coupling");
    if (!out) {
      std::fprintf(stderr, "hystloop-ctl: could not write %s\n", o.out.c_str());
      return 1;
    }
    std::printf("hystloop-ctl: wrote %s (hystloop-compensator --params %s)\n", o.out.c_str(), o.out.c_str());
  }
  return 0;
}

}  // namespace hystloop::ctl
