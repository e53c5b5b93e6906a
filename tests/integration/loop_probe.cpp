// The integration tests' hands and eyes on a running bridge + compensator (udpm inside
// tools/netns-run):
//
//   loop_probe record  --dir D [--seconds S] [--rt-priority N] [--axis A]   until SIGTERM or S seconds: HX_SENSOR ->
//   D/sensor.csv, HX_COMMAND -> D/command.csv, HX_SIM_TRUTH -> D/truth.csv (seq,y_true_m),
//                                                HX_STATUS -> D/status.log (one line per report:
//                                                process=P state=S ... counters ... host=H pid=N detail=D)
//   loop_probe control --command arm|disarm|set_mode|set_gains|start_experiment|stop_experiment|
//                                reset_counters|shutdown [--target P] [--mode N] [--kp --ki --kd]
//   loop_probe inject  --target bridge|compensator [--count N]
//                      malformed (truncated), wrong-type, non-finite and out-of-range messages on
//                      every input channel of that service (N of each)
//   loop_probe trajectory --version V --shape N --amplitude-m A --frequency-hz F --blend-s B
//   loop_probe params  --version V --c1 --c2 --c3 [--valid 0|1]
//   loop_probe analyze --dir D --u-min --u-max --slew --ramp --dt --watchdog
//                      checks the recorded samples: never outside [u_min, u_max], never a step
//                      above max(slew, ramp) * dt, every watchdog trip within watchdog_s + 5 ticks
//                      of the last command applied; prints key=value figures. Exit 1 on a violation.
//   loop_probe wait-tick --seq N [--timeout S]   exit 0 (printing the tick) once HX_SENSOR carries tick N or
//                      later, 1 after S seconds (10) without it
//   loop_probe status-value --dir D --process P --key K   the last (not STOPPING) report's value of K
//                      (a counter name, or state/late/rejected/latency_p50_us/... or detail)
#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "core/cli.hpp"
#include "core/process.hpp"
#include "lcm/blocks.hpp"
#include "lcm/channels.hpp"
#include "lcm/connection.hpp"
#include "lcm/publisher.hpp"
#include "lcm/subscription.hpp"
#include "hystloop/sim_truth_t.hpp"

namespace hystloop {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::int64_t now_utime() {
  using namespace std::chrono;
  return duration_cast<microseconds>(system_clock::now().time_since_epoch()).count();
}

void pause_ms(int ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); }

// Returns 0 as soon as a sensor block carries a tick >= seq (printing it), 1 after timeout_s
// without one. A script waits on the loop itself this way: a file the recorder writes trails it,
// and a shell poll forks per look, which on a loaded machine overshoots by tenths of a second.
int wait_tick(lcm::LCM& lcm, const ChannelNames& ch, std::int64_t seq, double timeout_s) {
  std::int64_t newest = -1;
  Subscription<sensor_block_t> s(lcm, ch.sensor, [&](const sensor_block_t& m, std::int64_t) {
    for_each_tick(m, [&](const SensorTick& t) { newest = std::max(newest, t.seq); });
  });
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (newest < seq && std::chrono::steady_clock::now() < end) handle_pending(lcm, std::chrono::milliseconds(5));
  if (newest < seq) {
    std::fprintf(stderr, "loop_probe: no tick %lld within %g s (newest seen: %lld)\n", static_cast<long long>(seq),
                 timeout_s, static_cast<long long>(newest));
    return 1;
  }
  std::printf("%lld\n", static_cast<long long>(newest));
  return 0;
}

int record(lcm::LCM& lcm, const ChannelNames& ch, const std::string& dir, double seconds, int rt_priority,
           std::size_t axis) {
  install_stop_handlers();  // SIGTERM ends the recording cleanly
  // A recorder starved for longer than its socket buffer (~0.5 s of traffic) loses samples.
  if (rt_priority > 0) set_realtime_priority(rt_priority);
  std::FILE* sensor = std::fopen((dir + "/sensor.csv").c_str(), "w");
  std::FILE* command = std::fopen((dir + "/command.csv").c_str(), "w");
  std::FILE* status = std::fopen((dir + "/status.log").c_str(), "w");
  std::FILE* truth = std::fopen((dir + "/truth.csv").c_str(), "w");
  if (!sensor || !command || !status || !truth) {
    std::fprintf(stderr, "loop_probe: cannot write into %s\n", dir.c_str());
    return 2;
  }
  std::fprintf(sensor, "seq,utime,u_V,y_m,flags,y_ref_m,u_ff_V,u_fb_V\n");
  std::fprintf(command, "seq,sample_seq,u_ff_V,y_ref_m,params_version,mode\n");
  std::fprintf(truth, "seq,y_true_m\n");
  Subscription<sensor_block_t>::Options so;
  so.queue_capacity = 100000;
  Subscription<sensor_block_t> s(
      lcm, ch.sensor,
      [&](const sensor_block_t& m, std::int64_t) {
        if (axis >= axes_of(m)) return;
        for_each_tick(
            m,
            [&](const SensorTick& t) {
              std::fprintf(sensor, "%lld,%lld,%.17g,%.17g,%d,%.17g,%.17g,%.17g\n", static_cast<long long>(t.seq),
                           static_cast<long long>(t.utime), t.u_V, t.y_m, t.flags, t.y_ref_m, t.u_ff_V, t.u_fb_V);
            },
            axis);
      },
      so);
  Subscription<command_block_t>::Options co;
  co.queue_capacity = 100000;
  co.check = nullptr;  // record what the bridge is sent, including what it rejects
  Subscription<command_block_t> c(
      lcm, ch.command,
      [&](const command_block_t& m, std::int64_t) {
        if (!arrays_consistent(m) || axis >= axes_of(m)) return;
        for_each_tick(
            m,
            [&](const CommandTick& t) {
              std::fprintf(command, "%lld,%lld,%.17g,%.17g,%d,%d\n", static_cast<long long>(t.seq),
                           static_cast<long long>(m.sample_seq), t.u_ff_V, t.y_ref_m, t.params_version, t.mode);
            },
            axis);
      },
      co);
  Subscription<sim_truth_t>::Options to;
  to.queue_capacity = 100000;
  Subscription<sim_truth_t> tr(
      lcm, ch.sim_truth,
      [&](const sim_truth_t& m, std::int64_t) {
        long long seq = m.seq;
        for (const double y : axis_truth(m, axis)) std::fprintf(truth, "%lld,%.17g\n", seq++, y);
      },
      to);
  Subscription<service_status_t> st(lcm, ch.status, [&](const service_status_t& m, std::int64_t) {
    std::fprintf(status,
                 "process=%s state=%d late=%lld rejected=%lld loop_p50_us=%.3f loop_p99_us=%.3f loop_max_us=%.3f "
                 "latency_p50_us=%.3f latency_p99_us=%.3f latency_max_us=%.3f",
                 m.process.c_str(), m.state, static_cast<long long>(m.late), static_cast<long long>(m.rejected),
                 m.loop_p50_us, m.loop_p99_us, m.loop_max_us, m.latency_p50_us, m.latency_p99_us, m.latency_max_us);
    for (int i = 0; i < m.n_counters; ++i) {
      std::fprintf(status, " %s=%lld", m.counter_names[static_cast<std::size_t>(i)].c_str(),
                   static_cast<long long>(m.counter_values[static_cast<std::size_t>(i)]));
    }
    // Who sent it: two processes of one name (a restarted or a foreign one) are told apart.
    std::fprintf(status, " host=%s pid=%d detail=%s\n", m.host.c_str(), static_cast<int>(m.pid), m.detail.c_str());
    std::fflush(status);
  });
  std::fclose(std::fopen((dir + "/recording").c_str(), "w"));  // ready marker
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!stop_requested() && std::chrono::steady_clock::now() < end) {
    handle_pending(lcm, std::chrono::milliseconds(10));
  }
  std::fclose(sensor);
  std::fclose(command);
  std::fclose(status);
  std::fclose(truth);
  std::printf(
      "recorded %llu samples, %llu commands, %llu true-position blocks, %llu status reports\n",
      static_cast<unsigned long long>(s.counters().accepted), static_cast<unsigned long long>(c.counters().accepted),
      static_cast<unsigned long long>(tr.counters().accepted), static_cast<unsigned long long>(st.counters().accepted));
  return 0;
}

struct ControlArgs {
  std::string command;
  std::string target;
  int mode = 2;
  double kp = 0, ki = 0, kd = 0;
};

int control(lcm::LCM& lcm, const ChannelNames& ch, const ControlArgs& a) {
  static const std::map<std::string, std::int8_t> commands = {{"set_mode", control_t::SET_MODE},
                                                              {"set_gains", control_t::SET_GAINS},
                                                              {"arm", control_t::ARM},
                                                              {"disarm", control_t::DISARM},
                                                              {"start_experiment", control_t::START_EXPERIMENT},
                                                              {"stop_experiment", control_t::STOP_EXPERIMENT},
                                                              {"reset_counters", control_t::RESET_COUNTERS},
                                                              {"shutdown", control_t::SHUTDOWN}};
  const auto it = commands.find(a.command);
  if (it == commands.end()) {
    std::fprintf(stderr, "loop_probe: unknown control command %s\n", a.command.c_str());
    return 2;
  }
  control_t m{};
  m.utime = now_utime();
  m.request_id = m.utime;  // unique enough for a test
  m.command = it->second;
  m.target = a.target;
  m.mode = static_cast<std::int8_t>(m.command == control_t::SET_MODE ? a.mode : 0);
  m.kp = a.kp;
  m.ki = a.ki;
  m.kd = a.kd;
  m.experiment = m.command == control_t::START_EXPERIMENT ? "sine" : "";
  m.experiment_amplitude_V = m.command == control_t::START_EXPERIMENT ? 100.0 : 0.0;
  m.experiment_frequency_Hz = m.command == control_t::START_EXPERIMENT ? 10.0 : 0.0;
  m.experiment_duration_s = m.command == control_t::START_EXPERIMENT ? 1.0 : 0.0;
  Publisher<control_t> pub(lcm, ch.control);
  for (int i = 0; i < 3; ++i) {  // a receiver acts on a request_id once
    if (!pub.publish(m)) return 1;
    pause_ms(10);
  }
  return 0;
}

// A valid one-tick sensor block (a probe's bad messages are variations of it).
sensor_block_t one_tick_sensor_block() {
  sensor_block_t s{};
  begin_block(s, 1, now_utime(), 1e-4);
  append_tick(s, SensorTick{});
  return s;
}

// Publishes `msg` encoded, cut to half its length.
template <class T>
void publish_truncated(lcm::LCM& lcm, const std::string& channel, const T& msg) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(msg.getEncodedSize()));
  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  lcm.publish(channel, buf.data(), static_cast<unsigned>(buf.size() / 2));
}

template <class T>
void publish_unchecked(lcm::LCM& lcm, const std::string& channel, const T& msg) {
  Publisher<T> pub(lcm, channel, nullptr);
  pub.publish(msg);
}

control_t valid_control(std::int64_t id) {
  control_t m{};
  m.utime = now_utime();
  m.request_id = id;
  m.command = control_t::SET_GAINS;
  m.target = "nobody";  // valid on the wire, addressed to no one
  return m;
}

// N of each: truncated, wrong type, non-finite, out of range, on each input channel of `target`;
// and N blocks of two axes on the block channel (HX_COMMAND, HX_SENSOR).
int inject(lcm::LCM& lcm, const ChannelNames& ch, const std::string& target, int count) {
  const std::int64_t base_id = now_utime();
  for (int i = 0; i < count; ++i) {
    // HX_CONTROL (both services).
    control_t c = valid_control(base_id + i);
    publish_truncated(lcm, ch.control, c);
    publish_unchecked(lcm, ch.control, one_tick_sensor_block());  // wrong type
    c.kp = std::numeric_limits<double>::infinity();               // NaN is valid here: "keep the gain in force"
    publish_unchecked(lcm, ch.control, c);
    c.kp = 0.0;
    c.command = 99;
    publish_unchecked(lcm, ch.control, c);
    if (target == "bridge") {
      command_block_t m{};
      begin_block(m, 1, now_utime(), -1);
      append_tick(m, CommandTick{1, 0.0, 0.0, 0, command_block_t::MODE_MEM});
      publish_truncated(lcm, ch.command, m);
      publish_unchecked(lcm, ch.command, control_t{});  // wrong type
      m.u_ff_V[0] = kNaN;
      publish_unchecked(lcm, ch.command, m);
      m.u_ff_V[0] = 1e6;  // beyond any amplifier: a unit mistake
      publish_unchecked(lcm, ch.command, m);
      command_block_t xy{};  // valid, but planned for two axes: the one-axis bridge refuses it whole
      begin_block(xy, 1, now_utime(), -1, 2);
      const std::array<CommandTick, 2> both{CommandTick{1, 0.0, 0.0, 0, command_block_t::MODE_MEM},
                                            CommandTick{1, 0.0, 0.0, 0, command_block_t::MODE_MEM}};
      append_tick(xy, both);
      publish_unchecked(lcm, ch.command, xy);
    } else {
      sensor_block_t s = one_tick_sensor_block();
      publish_truncated(lcm, ch.sensor, s);
      publish_unchecked(lcm, ch.sensor, control_t{});
      s.y_m[0] = kNaN;
      publish_unchecked(lcm, ch.sensor, s);
      s.y_m[0] = 0.0;
      s.seq = -5;
      publish_unchecked(lcm, ch.sensor, s);
      sensor_block_t xy{};  // valid, but of two axes: the one-axis compensator refuses it whole
      begin_block(xy, 1, now_utime(), 1e-4, 2);
      const std::array<SensorTick, 2> both{};
      append_tick(xy, both);
      publish_unchecked(lcm, ch.sensor, xy);

      trajectory_t t{};
      t.utime = now_utime();
      t.version = 1000 + i;
      t.shape = trajectory_t::SINE;
      t.frequency_Hz = 1.0;
      publish_truncated(lcm, ch.trajectory, t);
      publish_unchecked(lcm, ch.trajectory, control_t{});
      t.amplitude_m = kNaN;
      publish_unchecked(lcm, ch.trajectory, t);
      t.amplitude_m = 0.0;
      t.shape = 42;
      publish_unchecked(lcm, ch.trajectory, t);

      mem_params_t p{};
      p.utime = now_utime();
      p.version = 1000 + i;
      p.c1 = 5e-9;
      p.c2 = 1e-12;
      p.c3 = 1.2;
      p.valid = true;
      publish_truncated(lcm, ch.params, p);
      publish_unchecked(lcm, ch.params, control_t{});
      p.c1 = kNaN;
      publish_unchecked(lcm, ch.params, p);
      p.c1 = -1e-9;
      publish_unchecked(lcm, ch.params, p);
    }
    pause_ms(5);
  }
  return 0;
}

// The most ticks any command block planned ahead of the last sample the compensator had.
std::int64_t max_planned_ahead(const std::string& dir) {
  std::ifstream in(dir + "/command.csv");
  std::string line;
  std::getline(in, line);
  std::int64_t worst = 0;
  while (std::getline(in, line)) {
    long long seq = 0, sample_seq = 0;
    if (std::sscanf(line.c_str(), "%lld,%lld", &seq, &sample_seq) == 2 && sample_seq >= 0) {
      worst = std::max<std::int64_t>(worst, seq - sample_seq);
    }
  }
  return worst;
}

int analyze(const std::string& dir, double u_min, double u_max, double slew, double ramp, double dt, double watchdog) {
  std::vector<double> run_errors;  // y - y_ref over the current armed run
  std::ifstream in(dir + "/sensor.csv");
  std::string line;
  std::getline(in, line);
  const double max_step = std::max(slew, ramp) * dt * (1 + 1e-9) + 1e-9;
  const auto watchdog_ticks = static_cast<std::int64_t>(std::llround(watchdog / dt));
  std::int64_t n = 0, gaps = 0, out_of_range = 0, too_fast = 0, trips = 0, slow_trips = 0, applied = 0, late_ticks = 0;
  std::int64_t prev_seq = -1, last_applied = -1, worst_trip_ticks = 0;
  double prev_u = kNaN, max_du = 0.0;
  bool prev_safe = true;
  while (std::getline(in, line)) {
    long long seq = 0, utime = 0;
    double u = 0, y = 0, y_ref = 0;
    int flags = 0;
    char ref_text[64] = {0};
    if (std::sscanf(line.c_str(), "%lld,%lld,%lf,%lf,%d,%63[^,]", &seq, &utime, &u, &y, &flags, ref_text) != 6)
      continue;
    y_ref = std::strtod(ref_text, nullptr);  // "nan" (no reference) reads as NaN
    ++n;
    const bool consecutive = prev_seq >= 0 && seq == prev_seq + 1;
    if (prev_seq >= 0 && !consecutive) ++gaps;
    if (!(u >= u_min && u <= u_max)) ++out_of_range;
    if (consecutive && std::isfinite(prev_u)) {
      const double du = std::abs(u - prev_u);
      max_du = std::max(max_du, du);
      if (du > max_step) ++too_fast;
    }
    const bool safe = (flags & sensor_block_t::SAFE_STATE) != 0;
    const bool late = !safe && (flags & sensor_block_t::LATE_COMMAND) != 0;
    const bool fresh = !safe && !late;
    if (late) ++late_ticks;
    if (fresh) {
      last_applied = seq;
      ++applied;
    }
    // An armed run starts after a safe stretch (the start, a trip, a disarm) and ends with the
    // next one: the stop's ramp to the safe voltage ends the last run, it does not erase it.
    if (!safe && prev_safe) run_errors.clear();
    if (!safe && std::isfinite(y_ref)) run_errors.push_back(y - y_ref);
    if (safe && !prev_safe && last_applied >= 0) {  // a trip (or a disarm) after commands were applied
      ++trips;
      const std::int64_t ticks = seq - last_applied;
      worst_trip_ticks = std::max(worst_trip_ticks, ticks);
      if (ticks > watchdog_ticks + 5) ++slow_trips;
    }
    prev_safe = safe;
    prev_seq = seq;
    prev_u = u;
  }
  // Tracking over the second half of the last armed run.
  double sum2 = 0.0;
  const std::size_t half = run_errors.size() / 2;
  for (std::size_t i = half; i < run_errors.size(); ++i) sum2 += run_errors[i] * run_errors[i];
  const std::size_t n_track = run_errors.size() - half;
  std::printf("last_run_ticks=%zu\ntracking_rms_m=%.6g\n", run_errors.size(),
              n_track > 0 ? std::sqrt(sum2 / static_cast<double>(n_track)) : kNaN);
  std::printf(
      "samples=%lld\nseq_gaps=%lld\napplied=%lld\nout_of_range=%lld\nmax_step_V=%.6g\nallowed_step_V=%.6g\n"
      "too_fast=%lld\nsafe_entries=%lld\nworst_trip_ticks=%lld\nwatchdog_ticks=%lld\nslow_trips=%lld\n"
      "late_ticks=%lld\nmax_planned_ahead_ticks=%lld\n",
      static_cast<long long>(n), static_cast<long long>(gaps), static_cast<long long>(applied),
      static_cast<long long>(out_of_range), max_du, max_step, static_cast<long long>(too_fast),
      static_cast<long long>(trips), static_cast<long long>(worst_trip_ticks), static_cast<long long>(watchdog_ticks),
      static_cast<long long>(slow_trips), static_cast<long long>(late_ticks),
      static_cast<long long>(max_planned_ahead(dir)));
  return (n > 0 && out_of_range == 0 && too_fast == 0 && slow_trips == 0) ? 0 : 1;
}

// The last status line of `process`, and one value from it.
int status_value(const std::string& dir, const std::string& process, const std::string& key) {
  std::ifstream in(dir + "/status.log");
  std::string line, last;
  while (std::getline(in, line)) {
    // The last report before STOPPING (which says only that).
    if (line.rfind("process=" + process + " ", 0) == 0 && line.find(" state=4 ") == std::string::npos) last = line;
  }
  if (last.empty()) {
    std::fprintf(stderr, "loop_probe: no status from %s\n", process.c_str());
    return 1;
  }
  if (key == "detail") {
    const auto at = last.find(" detail=");
    std::printf("%s\n", last.substr(at + 8).c_str());
    return 0;
  }
  std::istringstream words(last.substr(0, last.find(" detail=")));
  std::string word;
  while (words >> word) {
    if (word.rfind(key + "=", 0) == 0) {
      std::printf("%s\n", word.substr(key.size() + 1).c_str());
      return 0;
    }
  }
  std::fprintf(stderr, "loop_probe: %s reports no %s\n", process.c_str(), key.c_str());
  return 1;
}

}  // namespace
}  // namespace hystloop

int run_probe(int argc, char** argv) {
  using namespace hystloop;
  CLI::App app{"loop_probe: records, drives and checks a running bridge + compensator"};
  app.require_subcommand(1);
  std::string url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
  std::string prefix = "HX_";
  app.add_option("--url", url);
  app.add_option("--prefix", prefix);

  std::string dir;
  double seconds = 5;
  int rt_priority = 0;
  auto* rec = app.add_subcommand("record");
  rec->add_option("--dir", dir)->required();
  rec->add_option("--seconds", seconds, "at most this long; SIGTERM stops it earlier");
  rec->add_option("--rt-priority", rt_priority, "SCHED_FIFO priority (0 = normal)");
  std::size_t axis = 0;
  rec->add_option("--axis", axis, "the axis of a multi-axis stage to record (0: x, 1: y, 2: z)");

  ControlArgs ca;
  auto* ctl = app.add_subcommand("control");
  ctl->add_option("--command", ca.command)->required();
  ctl->add_option("--target", ca.target);
  ctl->add_option("--mode", ca.mode);
  ctl->add_option("--kp", ca.kp);
  ctl->add_option("--ki", ca.ki);
  ctl->add_option("--kd", ca.kd);

  std::string target;
  int count = 5;
  auto* inj = app.add_subcommand("inject");
  inj->add_option("--target", target)->required();
  inj->add_option("--count", count);

  trajectory_t traj{};
  int shape = trajectory_t::COSINE;
  auto* tr = app.add_subcommand("trajectory");
  tr->add_option("--version", traj.version)->required();
  tr->add_option("--shape", shape);
  tr->add_option("--amplitude-m", traj.amplitude_m);
  tr->add_option("--offset-m", traj.offset_m);
  tr->add_option("--frequency-hz", traj.frequency_Hz);
  tr->add_option("--blend-s", traj.blend_s);

  mem_params_t params{};
  int valid = 1;
  auto* pa = app.add_subcommand("params");
  pa->add_option("--version", params.version)->required();
  pa->add_option("--c1", params.c1)->required();
  pa->add_option("--c2", params.c2)->required();
  pa->add_option("--c3", params.c3)->required();
  pa->add_option("--valid", valid);

  double u_min = -250, u_max = 250, slew = 5e4, ramp = 1e3, dt = 1e-4, watchdog = 2e-3;
  auto* an = app.add_subcommand("analyze");
  an->add_option("--dir", dir)->required();
  an->add_option("--u-min", u_min);
  an->add_option("--u-max", u_max);
  an->add_option("--slew", slew);
  an->add_option("--ramp", ramp);
  an->add_option("--dt", dt);
  an->add_option("--watchdog", watchdog);

  std::int64_t wait_seq = 0;
  double wait_timeout_s = 10;
  auto* wt = app.add_subcommand("wait-tick");
  wt->add_option("--seq", wait_seq)->required();
  wt->add_option("--timeout", wait_timeout_s, "give up after this long [s]");

  std::string process, key;
  auto* sv = app.add_subcommand("status-value");
  sv->add_option("--dir", dir)->required();
  sv->add_option("--process", process)->required();
  sv->add_option("--key", key)->required();

  if (const auto exit_code = hystloop::parse_cli(app, argc, argv)) return *exit_code;
  try {
    if (*an) return analyze(dir, u_min, u_max, slew, ramp, dt, watchdog);
    if (*sv) return status_value(dir, process, key);
    const ChannelNames ch(prefix);
    auto lcm = open_lcm(url);
    if (*rec) return record(*lcm, ch, dir, seconds, rt_priority, axis);
    if (*ctl) return control(*lcm, ch, ca);
    if (*inj) return inject(*lcm, ch, target, count);
    if (*wt) return wait_tick(*lcm, ch, wait_seq, wait_timeout_s);
    if (*tr) {
      traj.utime = now_utime();
      traj.shape = static_cast<std::int8_t>(shape);
      for (int i = 0; i < 3; ++i) {
        publish_unchecked(*lcm, ch.trajectory, traj);  // repeats: the compensator applies a version once
        pause_ms(10);
      }
      return 0;
    }
    if (*pa) {
      params.utime = now_utime();
      params.valid = static_cast<std::int8_t>(valid != 0 ? 1 : 0);
      params.source = "loop_probe";
      publish_unchecked(*lcm, ch.params, params);
      return 0;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "loop_probe: %s\n", e.what());
    return 2;
  }
  return 2;
}

int main(int argc, char** argv) {
  try {
    return run_probe(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "loop_probe: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "loop_probe: unknown error\n");
  }
  return 1;
}
