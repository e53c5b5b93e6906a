#include "rig_client.hpp"

#include <unistd.h>

#include <cmath>
#include <limits>
#include <unordered_map>
#include <utility>

#include <spdlog/fmt/fmt.h>

#include "core/clock.hpp"
#include "core/errors.hpp"
#include "ctl_health.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/sim_truth_t.hpp"
#include "lcm/blocks.hpp"
#include "lcm/message_checks.hpp"
#include "lcm/rig_auth.hpp"
#include "lcm/status_counters.hpp"
#include "lcm/subscription.hpp"

namespace hystloop::ctl {

namespace {

// The reason a request was not confirmed: each process's answer, then the tool's summary line.
[[noreturn]] void throw_not_confirmed(const ControlResult& r) {
  std::string what;
  for (const std::string& line : r.answers) what += line + "\n";
  throw RigError(what + r.error);
}

// Appends every tick of `b` (all its axes) to `out`; returns the row of its first tick.
std::size_t append_block(const sensor_block_t& b, RecordedTicks& out) {
  const std::size_t first = out.seq.size();
  const std::size_t axes = axes_of(b);
  out.axes = static_cast<int>(axes);
  out.dt_s = b.dt_s;
  for (std::size_t i = 0, n = ticks_of(b); i < n; ++i) {
    for (std::size_t a = 0; a < axes; ++a) {
      const SensorTick t = sensor_tick(b, i, a);
      out.seq.push_back(t.seq);
      out.axis.push_back(static_cast<std::int32_t>(a));
      out.u_V.push_back(t.u_V);
      out.u_ff_V.push_back(t.u_ff_V);
      out.u_fb_V.push_back(t.u_fb_V);
      out.y_ref_m.push_back(t.y_ref_m);
      out.y_m.push_back(t.y_m);
      out.y_true_m.push_back(std::numeric_limits<double>::quiet_NaN());
      out.flags.push_back(t.flags);
    }
  }
  ++out.blocks;
  return first;
}

// Writes a truth block over the rows of its sensor block (same ticks, same axes; else ignored).
void apply_truth(const sim_truth_t& t, std::size_t first, RecordedTicks& out) {
  const std::size_t n = t.y_true_m.size();
  if (first + n > out.seq.size() || out.seq[first] != t.seq) return;
  for (std::size_t v = 0; v < n; ++v) out.y_true_m[first + v] = t.y_true_m[v];
}

}  // namespace

void RigClientOptions::validate() const {
  require_positive("timeout", timeout_s);
  if (bridge.empty()) throw ParameterError("bridge", "must name the bridge's process");
  if (compensator.empty()) throw ParameterError("compensator", "must name the compensator's process");
}

namespace {
const LinkOptions& checked(const RigClientOptions& o) {
  o.validate();
  // Signing is the process's (every endpoint built after this signs): as hystloop-ctl --key-file.
  if (!o.key_file.empty()) set_process_rig_auth(rig_auth_from_key_file(o.key_file, "key_file"));
  return o.link;
}
}  // namespace

RigClient::RigClient(const RigClientOptions& options) : options_(options), link_(checked(options)) {}

std::vector<ProcessReport> RigClient::status(double listen_s) {
  require_positive("listen", listen_s);
  std::map<std::string, service_status_t> last;
  Subscription<service_status_t> sub(link_.lcm(), link_.channels().status,
                                     [&](const service_status_t& s, std::int64_t) { last[s.process] = s; });
  const auto deadline = after(listen_s);
  while (Clock::now() < deadline) {
    if (!receive(link_, deadline, std::chrono::microseconds(20'000))) {
      throw RigError("LCM failed while listening on " + link_.channels().status + " (" + link_.url() + ")");
    }
  }
  std::vector<ProcessReport> out;
  for (const auto& [name, s] : last) {
    ProcessReport r;
    r.process = name;
    r.state = state_name(s.state);
    r.detail = s.detail;
    r.host = s.host;
    r.utime = s.utime;
    r.late = s.late;
    r.rejected = s.rejected;
    for (std::size_t i = 0; i < s.counter_names.size() && i < s.counter_values.size(); ++i) {
      r.counters.emplace_back(s.counter_names[i], s.counter_values[i]);
    }
    out.push_back(std::move(r));
  }
  return out;
}

void RigClient::control(std::int8_t command, const std::string& target, const std::string& what,
                        const std::function<void(control_t&)>& fill, const char* owner, StateCheck state) {
  const std::int64_t now = wall_utime();
  control_t msg = make_control(command, target, new_request_id(now, static_cast<int>(::getpid())), now);
  if (fill) fill(msg);
  if (check_message(msg) != Verdict::kOk) throw ParameterError(what, "refused by the message contract");
  AckOptions ack;
  ack.timeout_s = options_.timeout_s;
  if (!target.empty() || owner != nullptr) ack.expected = {target.empty() ? std::string(owner) : target};
  ack.state = std::move(state);
  const ControlResult r = request_control(link_, msg, what, ack);
  if (!r.confirmed) throw_not_confirmed(r);
}

void RigClient::arm() { control(control_t::ARM, options_.bridge, "ARM", {}, nullptr, counter_is("armed", 1)); }

void RigClient::disarm() { control(control_t::DISARM, options_.bridge, "DISARM", {}, nullptr, counter_is("armed", 0)); }

void RigClient::set_gains(const GainsRequest& gains) {
  if (gains.empty())
    throw ParameterError("gains", "give at least one of kp, ki, kd, notch_hz, notch_q, notch2_hz, notch2_q");
  gains.validate();
  control(
      control_t::SET_GAINS, options_.bridge, "SET_GAINS", [&](control_t& msg) { apply(gains, msg); }, nullptr);
}

void RigClient::set_mode(const std::string& mode) {
  const std::int8_t m = parse_mode(mode);
  control(
      control_t::SET_MODE, options_.compensator, "SET_MODE " + mode, [m](control_t& msg) { msg.mode = m; }, nullptr,
      counter_is("mode", m));
}

void RigClient::learn(const std::string& what) {
  const std::int8_t l = parse_learning(what);
  control(
      control_t::SET_LEARNING, options_.compensator, "SET_LEARNING " + what, [l](control_t& msg) { msg.learning = l; },
      nullptr);
}

void RigClient::experiment(const ExperimentRequest& experiment, int axis) {
  experiment.validate();
  if (axis < 0 || axis > 2) throw ParameterError("axis", "must be 0, 1 or 2 (x, y, z)");
  control(
      control_t::START_EXPERIMENT, options_.compensator, "START_EXPERIMENT",
      [&](control_t& msg) {
        apply(experiment, msg);
        msg.axis = static_cast<std::int8_t>(axis);
      },
      nullptr);
}

void RigClient::stop_experiment() {
  control(control_t::STOP_EXPERIMENT, options_.compensator, "STOP_EXPERIMENT", {}, nullptr);
}

std::string RigClient::set_trajectory(const TrajectoryRequest& request) {
  const std::int64_t now = wall_utime();
  const trajectory_t msg = make_trajectory(request, now, now);  // validates; version: wall time, as ctl's
  VerdictOptions o;
  o.timeout_s = options_.timeout_s;
  o.compensator_process = options_.compensator;
  const VerdictResult r = send_trajectory(link_, msg, o);
  if (!r.error.empty()) throw RigError(r.error);
  const std::string how = r.verdict.outcome == TrajectoryOutcome::kShaped ? "shaped" : "accepted";
  return r.verdict.detail.empty() ? how : how + ": " + r.verdict.detail;
}

std::int32_t RigClient::set_params(ParamsRequest request) {
  if (request.version <= 0) {
    request.version = 1;
    request.validate();  // refuse bad values before listening for the version
    request.version = next_params_version(link_, 1.5);
  }
  request.validate();
  const mem_params_t msg = make_params(request, wall_utime());
  if (!publish_repeated(link_.lcm(), link_.channels().params, msg)) {
    throw RigError("could not publish on " + link_.channels().params);
  }
  const StatusWait w = wait_for_status(
      link_, options_.compensator, counter_is(params_version_counter(request.axis), msg.version), options_.timeout_s);
  if (!w.satisfied) {
    throw RigError(fmt::format("'{}' did not adopt parameters v{} within {:g} s{}", options_.compensator, msg.version,
                               options_.timeout_s,
                               w.last.count(options_.compensator) == 0 ? " (no status from it: is it running?)"
                                                                       : " (refused or stale: see its status)"));
  }
  return msg.version;
}

RecordedTicks RigClient::record(double seconds) {
  require_positive("seconds", seconds);
  RecordedTicks out;
  // 10 kHz over `seconds`, a few axes: reserved once, so that appending does not reallocate often.
  const auto expected = static_cast<std::size_t>(seconds * 1e4 * 1.05) + 1024;
  for (auto* v : {&out.u_V, &out.u_ff_V, &out.u_fb_V, &out.y_ref_m, &out.y_m, &out.y_true_m}) v->reserve(expected);
  out.seq.reserve(expected);
  out.axis.reserve(expected);
  out.flags.reserve(expected);
  std::unordered_map<std::int64_t, std::size_t> first_row;  // by block seq
  std::unordered_map<std::int64_t, sim_truth_t> truth_early;
  std::int64_t next_seq = -1;
  bool recording = true;
  Subscription<sensor_block_t>::Options queue;
  queue.queue_capacity = 4000;  // 20 s of 200 blocks/s: a slow caller loses nothing
  Subscription<sensor_block_t> sensor(
      link_.lcm(), link_.channels().sensor,
      [&](const sensor_block_t& b, std::int64_t) {
        if (!recording) return;
        if (next_seq >= 0 && b.seq > next_seq) out.missing_ticks += static_cast<std::uint64_t>(b.seq - next_seq);
        if (next_seq >= 0 && b.seq < next_seq) return;  // a repeat (or a restarted bridge's old numbers)
        next_seq = b.seq + static_cast<std::int64_t>(ticks_of(b));
        const std::size_t row = append_block(b, out);
        first_row[b.seq] = row;
        if (const auto t = truth_early.find(b.seq); t != truth_early.end()) {
          apply_truth(t->second, row, out);
          truth_early.erase(t);
        }
      },
      queue);
  Subscription<sim_truth_t>::Options truth_queue;
  truth_queue.queue_capacity = 4000;
  Subscription<sim_truth_t> truth(
      link_.lcm(), link_.channels().sim_truth,
      [&](const sim_truth_t& t, std::int64_t) {
        if (const auto r = first_row.find(t.seq); r != first_row.end()) {
          apply_truth(t, r->second, out);
        } else if (recording) {
          truth_early[t.seq] = t;
        }
      },
      truth_queue);
  const auto deadline = after(seconds);
  while (Clock::now() < deadline) {
    if (!receive(link_, deadline, std::chrono::microseconds(50'000), 4096)) {
      throw RigError("LCM failed while recording (" + link_.url() + ")");
    }
  }
  // The last blocks' truths follow them: a little longer for those only.
  recording = false;
  const auto tail = after(0.1);
  while (Clock::now() < tail) {
    if (!receive(link_, tail, std::chrono::microseconds(20'000), 4096)) break;
  }
  if (out.blocks == 0) {
    throw RigError(
        fmt::format("no sensor blocks on {} in {:g} s: is the bridge running?", link_.channels().sensor, seconds));
  }
  return out;
}

std::optional<RecordedTicks> RigClient::next_block(double timeout_s) {
  require_positive("timeout", timeout_s);
  std::optional<RecordedTicks> out;
  Subscription<sensor_block_t> sensor(link_.lcm(), link_.channels().sensor, [&](const sensor_block_t& b, std::int64_t) {
    if (out) return;
    out.emplace();
    append_block(b, *out);
  });
  const auto deadline = after(timeout_s);
  while (!out && Clock::now() < deadline) {
    if (!receive(link_, deadline, std::chrono::microseconds(20'000), 1)) {
      throw RigError("LCM failed while waiting for a sensor block (" + link_.url() + ")");
    }
  }
  return out;
}

}  // namespace hystloop::ctl
