// A test program for the LCM plumbing across processes (tests/integration):
//
//   lcm_probe publish   --url U --prefix P --rounds N [--rate-hz R]
//   lcm_probe subscribe --url U --prefix P --rounds N [--timeout-s T] [--ready-file F]
//   lcm_probe write-log --file F --prefix P --rounds N      (an LCM event log, no network)
//   lcm_probe check-log --file F --prefix P --rounds N [--ignore-prefix Q]   (read one back, e.g. lcm-logger's;
//                       events on other channels fail it unless their names start with Q)
//   lcm_probe echo      --url U --prefix P --rounds N [--ready-file F]   answers N sensor blocks
//   lcm_probe ping      --url U --prefix P --rounds N [--rate-hz R]      round-trip percentiles
//
// Round k sends fixtures::sensor_block(k) and command_block(k) (1..10 ticks each, so the
// arrays' sizes vary); every 10th round (j = k / 10) also trajectory(j), params(j), model_params(j), status(j)
// and control(j). A receiver recovers k or j from the message, and requires every expected
// message exactly once, byte-identical to the fixture, with nothing rejected. Exit status
// 0 = all intact, 1 = something missing or altered.
#include <algorithm>
#include <chrono>
#include <vector>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include "lcm/channels.hpp"
#include "lcm/connection.hpp"
#include "lcm/message_fixtures.hpp"
#include "lcm/model_params_fixtures.hpp"
#include "lcm/publisher.hpp"
#include "lcm/subscription.hpp"
#include "integration/probe_common.hpp"

namespace hystloop {
namespace {

struct Options {
  std::string mode;
  std::string url;
  std::string prefix{kDefaultRigPrefix};
  std::string file;
  std::string ready_file;
  std::string ignore_prefix;  // check-log: events on channels with this prefix are not counted
  std::int64_t rounds = 100;
  double rate_hz = 2000.0;
  double timeout_s = 5.0;
};

Options parse(int argc, char** argv) {
  Options o;
  o.mode = probe::mode_of(argc, argv, "usage: lcm_probe publish|subscribe|write-log|check-log|echo|ping [options]");
  probe::parse_options(argc, argv,
                       {{"--url", &o.url},
                        {"--prefix", &o.prefix},
                        {"--file", &o.file},
                        {"--ready-file", &o.ready_file},
                        {"--ignore-prefix", &o.ignore_prefix},
                        {"--rounds", &o.rounds},
                        {"--rate-hz", &o.rate_hz},
                        {"--timeout-s", &o.timeout_s}});
  return o;
}

std::int64_t rare_rounds(std::int64_t rounds) { return (rounds + 9) / 10; }

// Calls emit(channel, message) for every message of round k, in order.
template <class Emit>
void emit_round(const ChannelNames& ch, std::int64_t k, Emit&& emit) {
  emit(ch.sensor, fixtures::sensor_block(k));
  emit(ch.command, fixtures::command_block(k));
  if (k % 10 == 0) {
    const std::int64_t j = k / 10;
    emit(ch.trajectory, fixtures::trajectory(j));
    emit(ch.params, fixtures::params(j));
    emit(ch.model, fixtures::model_params(j));
    emit(ch.status, fixtures::status(j));
    emit(ch.control, fixtures::control(j));
  }
}

// The fixture index a message carries.
std::int64_t index_of(const sensor_block_t& m) { return m.seq / fixtures::kRoundTicks; }
std::int64_t index_of(const command_block_t& m) { return m.sample_seq / fixtures::kRoundTicks; }
std::int64_t index_of(const trajectory_t& m) { return m.version - 1; }
std::int64_t index_of(const mem_params_t& m) { return m.version - 1; }
std::int64_t index_of(const model_params_t& m) { return m.version - 1; }
std::int64_t index_of(const service_status_t& m) { return m.pid - 4242; }
std::int64_t index_of(const control_t& m) { return m.request_id - 100; }
sensor_block_t fixture_for(const sensor_block_t*, std::int64_t i) { return fixtures::sensor_block(i); }
command_block_t fixture_for(const command_block_t*, std::int64_t i) { return fixtures::command_block(i); }
trajectory_t fixture_for(const trajectory_t*, std::int64_t i) { return fixtures::trajectory(i); }
mem_params_t fixture_for(const mem_params_t*, std::int64_t i) { return fixtures::params(i); }
model_params_t fixture_for(const model_params_t*, std::int64_t i) { return fixtures::model_params(i); }
service_status_t fixture_for(const service_status_t*, std::int64_t i) { return fixtures::status(i); }
control_t fixture_for(const control_t*, std::int64_t i) { return fixtures::control(i); }

// Subscribes to one channel and checks what arrives there against the fixtures. `queue` (0: LCM's
// default) sizes the subscription's queue.
template <class T>
class Expectation {
 public:
  Expectation(lcm::LCM& lcm, std::string channel, std::int64_t expected, int queue)
      : channel_(std::move(channel)),
        expected_(expected),
        subscription_(
            lcm, channel_, [this](const T& m, std::int64_t) { see(m); }, queued(queue)) {}

  void see(const T& msg) {
    const std::int64_t i = index_of(msg);
    const bool known = i >= 0 && i < expected_;
    if (known && !seen_.insert(i).second) {
      ++duplicates_;
    } else if (!known || fixtures::encode(msg) != fixtures::encode(fixture_for(static_cast<const T*>(nullptr), i))) {
      ++altered_;  // an index never sent, or a first copy that differs from what was
    }
  }
  // An event of a log file: true when it is on this channel (and then received as LCM would deliver it).
  bool receive(const lcm::LogEvent& event) {
    if (event.channel != channel_) return false;
    subscription_.receive(event.data, static_cast<std::size_t>(event.datalen), event.timestamp);
    return true;
  }
  bool complete() const { return static_cast<std::int64_t>(seen_.size()) == expected_; }
  bool report() const {
    const std::uint64_t rejected = subscription_.counters().rejected_total();
    const bool ok = complete() && altered_ == 0 && duplicates_ == 0 && rejected == 0;
    std::printf("%-16s expected %6lld  intact %6zu  altered %4lld  duplicate %4lld  rejected %4llu  %s\n",
                channel_.c_str(), static_cast<long long>(expected_), seen_.size(), static_cast<long long>(altered_),
                static_cast<long long>(duplicates_), static_cast<unsigned long long>(rejected), ok ? "ok" : "FAIL");
    return ok;
  }

 private:
  std::string channel_;
  std::int64_t expected_;
  std::set<std::int64_t> seen_;
  std::int64_t altered_ = 0;
  std::int64_t duplicates_ = 0;
  Subscription<T> subscription_;

  static typename Subscription<T>::Options queued(int queue) {
    typename Subscription<T>::Options options;
    options.queue_capacity = queue;
    return options;
  }
};

// All seven expectations, fed either by LCM or by a log file's events. `queue` sizes the queues of
// the channels with a message every round (sensor, command).
struct Expectations {
  Expectations(lcm::LCM& lcm, const ChannelNames& ch, std::int64_t rounds, int queue = 0)
      : sensor(lcm, ch.sensor, rounds, queue),
        command(lcm, ch.command, rounds, queue),
        trajectory(lcm, ch.trajectory, rare_rounds(rounds), 0),
        params(lcm, ch.params, rare_rounds(rounds), 0),
        model(lcm, ch.model, rare_rounds(rounds), 0),
        status(lcm, ch.status, rare_rounds(rounds), 0),
        control(lcm, ch.control, rare_rounds(rounds), 0) {}
  // Calls f on each expectation, in the order of a round.
  template <class F>
  void each(F&& f) {
    f(sensor), f(command), f(trajectory), f(params), f(model), f(status), f(control);
  }
  bool complete() {
    bool all = true;
    each([&](const auto& e) { all = all && e.complete(); });
    return all;
  }
  // Prints a line a channel; true when every one is intact.
  bool report() {
    bool ok = true;
    each([&](const auto& e) { ok = e.report() && ok; });
    return ok;
  }
  // A log file's event: true when it is on one of the seven channels.
  bool receive(const lcm::LogEvent& event) {
    bool ours = false;
    each([&](auto& e) { ours = ours || e.receive(event); });
    return ours;
  }
  Expectation<sensor_block_t> sensor;
  Expectation<command_block_t> command;
  Expectation<trajectory_t> trajectory;
  Expectation<mem_params_t> params;
  Expectation<model_params_t> model;
  Expectation<service_status_t> status;
  Expectation<control_t> control;
};

int publish(const Options& o) {
  const ChannelNames ch(o.prefix);
  auto lcm = open_lcm(o.url);
  Publisher<sensor_block_t> sensor(*lcm, ch.sensor);
  Publisher<command_block_t> command(*lcm, ch.command);
  Publisher<trajectory_t> trajectory(*lcm, ch.trajectory);
  Publisher<mem_params_t> params(*lcm, ch.params);
  Publisher<model_params_t> model(*lcm, ch.model);
  Publisher<service_status_t> status(*lcm, ch.status);
  Publisher<control_t> control(*lcm, ch.control);
  std::uint64_t failed = 0;
  const auto emit = [&](const std::string& channel, const auto& msg) {
    using T = std::decay_t<decltype(msg)>;
    bool ok = false;
    if constexpr (std::is_same_v<T, sensor_block_t>)
      ok = sensor.publish(msg);
    else if constexpr (std::is_same_v<T, command_block_t>)
      ok = command.publish(msg);
    else if constexpr (std::is_same_v<T, trajectory_t>)
      ok = trajectory.publish(msg);
    else if constexpr (std::is_same_v<T, mem_params_t>)
      ok = params.publish(msg);
    else if constexpr (std::is_same_v<T, model_params_t>)
      ok = model.publish(msg);
    else if constexpr (std::is_same_v<T, service_status_t>)
      ok = status.publish(msg);
    else
      ok = control.publish(msg);
    (void)channel;
    failed += ok ? 0 : 1;
  };
  // Paced, never bursting: after a stall the schedule starts again from now instead of sending the
  // missed rounds back to back (a burst overflows a receiver's 30-message LCM queue, e.g. lcm-logger's).
  const auto period =
      std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(1.0 / o.rate_hz));
  auto next = std::chrono::steady_clock::now();
  for (std::int64_t k = 0; k < o.rounds; ++k) {
    std::this_thread::sleep_until(next);
    emit_round(ch, k, emit);
    next = std::max(next + period, std::chrono::steady_clock::now());
  }
  std::printf("published %lld rounds, %llu failures\n", static_cast<long long>(o.rounds),
              static_cast<unsigned long long>(failed));
  return failed == 0 ? 0 : 1;
}

int subscribe(const Options& o) {
  const ChannelNames ch(o.prefix);
  auto lcm = open_lcm(o.url);
  Expectations expect(*lcm, ch, o.rounds, static_cast<int>(2 * o.rounds + 64));  // a slow start must not drop
  if (!o.ready_file.empty()) std::ofstream(o.ready_file) << "ready\n";

  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.timeout_s);
  while (!expect.complete() && std::chrono::steady_clock::now() < deadline) {
    if (handle_pending(*lcm, std::chrono::milliseconds(10)) < 0) {
      std::fprintf(stderr, "lcm_probe: LCM reported an error\n");
      return 1;
    }
  }
  handle_pending(*lcm, std::chrono::milliseconds(50));  // late duplicates would show here
  return expect.report() ? 0 : 1;
}

int write_log(const Options& o) {
  const ChannelNames ch(o.prefix);
  lcm::LogFile log(o.file, "w");
  if (!log.good()) throw std::runtime_error("cannot write " + o.file);
  std::int64_t number = 0;
  for (std::int64_t k = 0; k < o.rounds; ++k) {
    emit_round(ch, k, [&](const std::string& channel, const auto& msg) {
      auto bytes = fixtures::encode(msg);
      lcm::LogEvent event{};
      event.eventnum = number++;
      event.timestamp = fixtures::kBaseUtime + 100 * k;
      event.channel = channel;
      event.datalen = static_cast<int32_t>(bytes.size());
      event.data = bytes.data();
      if (log.writeEvent(&event) != 0) throw std::runtime_error("write failed: " + o.file);
    });
  }
  std::printf("wrote %lld events to %s\n", static_cast<long long>(number), o.file.c_str());
  return 0;
}

int check_log(const Options& o) {
  const ChannelNames ch(o.prefix);
  lcm::LogFile log(o.file, "r");
  if (!log.good()) throw std::runtime_error("cannot read " + o.file);
  // A memq LCM only to host the Subscriptions: events are fed to receive() directly.
  lcm::LCM lcm("memq://");
  Expectations expect(lcm, ch, o.rounds);
  std::int64_t other = 0;
  while (const lcm::LogEvent* event = log.readNextEvent()) {
    if (!expect.receive(*event) && (o.ignore_prefix.empty() || event->channel.rfind(o.ignore_prefix, 0) != 0)) ++other;
  }
  const bool ok = expect.report();
  if (other != 0) std::printf("%lld events on other channels\n", static_cast<long long>(other));
  return ok && other == 0 ? 0 : 1;
}

// Answers each sensor block k with command_block(k), as a compensator would.
int echo(const Options& o) {
  const ChannelNames ch(o.prefix);
  auto lcm = open_lcm(o.url);
  Publisher<command_block_t> command(*lcm, ch.command);
  std::int64_t answered = 0;
  Subscription<sensor_block_t>::Options so;
  so.queue_capacity = 1000;
  Subscription<sensor_block_t> sensor(
      *lcm, ch.sensor,
      [&](const sensor_block_t& m, std::int64_t) {
        answered += command.publish(fixtures::command_block(index_of(m))) ? 1 : 0;
      },
      so);
  if (!o.ready_file.empty()) std::ofstream(o.ready_file) << "ready\n";
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.timeout_s);
  while (answered < o.rounds && std::chrono::steady_clock::now() < deadline) {
    if (handle_pending(*lcm, std::chrono::milliseconds(10)) < 0) return 1;
  }
  return answered == o.rounds ? 0 : 1;
}

// Sends sensor blocks at rate R and times block -> command round trips through an echo process.
int ping(const Options& o) {
  using Clock = std::chrono::steady_clock;
  const ChannelNames ch(o.prefix);
  auto lcm = open_lcm(o.url);
  Publisher<sensor_block_t> sensor(*lcm, ch.sensor);
  std::vector<Clock::time_point> sent(static_cast<std::size_t>(o.rounds));
  std::vector<sensor_block_t> blocks;  // built before the clock starts
  for (std::int64_t k = 0; k < o.rounds; ++k) blocks.push_back(fixtures::sensor_block(k));
  std::vector<double> rtt_us;
  rtt_us.reserve(sent.size());
  Subscription<command_block_t>::Options co;
  co.queue_capacity = 1000;
  Subscription<command_block_t> command(
      *lcm, ch.command,
      [&](const command_block_t& m, std::int64_t) {
        const std::int64_t k = index_of(m);
        if (m.sample_seq >= 0 && k < o.rounds) {
          rtt_us.push_back(
              std::chrono::duration<double, std::micro>(Clock::now() - sent[static_cast<std::size_t>(k)]).count());
        }
      },
      co);
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / o.rate_hz));
  const auto start = Clock::now();
  for (std::int64_t k = 0; k < o.rounds; ++k) {
    const auto due = start + period * k;
    while (Clock::now() < due) {  // serve replies while waiting for the next tick
      handle_pending(*lcm, std::chrono::duration_cast<std::chrono::microseconds>(due - Clock::now()));
    }
    sent[static_cast<std::size_t>(k)] = Clock::now();
    sensor.publish(blocks[static_cast<std::size_t>(k)]);
  }
  const auto deadline = Clock::now() + std::chrono::seconds(2);
  while (static_cast<std::int64_t>(rtt_us.size()) < o.rounds && Clock::now() < deadline) {
    handle_pending(*lcm, std::chrono::milliseconds(10));
  }
  if (rtt_us.empty()) return 1;
  std::sort(rtt_us.begin(), rtt_us.end());
  const auto pct = [&](double p) {
    return rtt_us[static_cast<std::size_t>(p * static_cast<double>(rtt_us.size() - 1))];
  };
  std::printf("round trips %zu/%lld at %.0f Hz: p50 %.1f us  p99 %.1f us  max %.1f us\n", rtt_us.size(),
              static_cast<long long>(o.rounds), o.rate_hz, pct(0.5), pct(0.99), rtt_us.back());
  return static_cast<std::int64_t>(rtt_us.size()) == o.rounds ? 0 : 1;
}

int run(int argc, char** argv) {
  return probe::run_mode("lcm_probe", parse(argc, argv),
                         {{"publish", publish},
                          {"subscribe", subscribe},
                          {"write-log", write_log},
                          {"check-log", check_log},
                          {"echo", echo},
                          {"ping", ping}});
}

}  // namespace
}  // namespace hystloop

int main(int argc, char** argv) {
  return hystloop::probe::run_probe("lcm_probe", [&] { return hystloop::run(argc, argv); });
}
