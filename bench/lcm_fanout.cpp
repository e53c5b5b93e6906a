// hystloop-lcm-fanout: what a process pays for multicast traffic it does not want.
// With one udpm URL every process on the group receives every channel at the socket; LCM
// drops the channels nobody subscribed to only after recv(). bench/lcm-fanout runs a
// publisher and listeners subscribed to the channel, to another channel on the same URL,
// to another URL, and an idle process, and compares their CPU time.
//
//   hystloop-lcm-fanout publish --url U --channel C --rate HZ --bytes N --seconds S
//   hystloop-lcm-fanout listen  --url U --channel C --seconds S
//   hystloop-lcm-fanout listen  --idle --seconds S
//
// Each prints one JSON line at exit: publish {"published", "skipped", "cpu_s", "wall_s"},
// listen {"received", "cpu_s", "wall_s"} (cpu_s = user + system time of the process,
// getrusage; wall_s from the start of main()).

#include <poll.h>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include "core/cli.hpp"
#include "core/errors.hpp"
#include "core/periodic_timer.hpp"
#include "core/process.hpp"
#include "lcm/connection.hpp"
#include "lcm/url.hpp"

namespace {

using hystloop::monotonic_ns;

constexpr std::size_t kMaxChannelLength = 63;     // LCM's limit on a channel name
constexpr std::int64_t kMaxWaitNs = 100'000'000;  // the wait loop wakes at least every 100 ms

struct Options {
  std::string url;  // empty: $LCM_DEFAULT_URL, else hystloop's default (ttl=0)
  std::string channel;
  double seconds = 10.0;
  bool allow_network = false;
  double rate_hz = 1000.0;  // publish
  int bytes = 400;          // publish
  bool idle = false;        // listen
};

double cpu_seconds() noexcept {
  const auto usage = hystloop::read_resource_usage();
  return usage.user_cpu_s + usage.system_cpu_s;
}

double seconds_since(std::int64_t start_ns) noexcept { return 1e-9 * static_cast<double>(monotonic_ns() - start_ns); }

void check_channel(const std::string& channel) {
  if (channel.empty()) throw hystloop::ParameterError("channel", "must not be empty");
  if (channel.size() > kMaxChannelLength) {
    throw hystloop::ParameterError("channel",
                                   "LCM allows at most 63 characters (got " + std::to_string(channel.size()) + ")");
  }
}

int publish(const Options& opt, std::int64_t start_ns) {
  check_channel(opt.channel);
  auto lcm = hystloop::open_lcm(opt.url, opt.allow_network);
  const std::int64_t period = hystloop::period_ns_from_rate_hz(opt.rate_hz);
  const auto wanted = static_cast<std::uint64_t>(std::llround(opt.seconds * 1e9 / static_cast<double>(period)));
  std::vector<std::uint8_t> payload(static_cast<std::size_t>(opt.bytes), 0x5a);

  hystloop::PeriodicTimer timer(period);  // clock_nanosleep(TIMER_ABSTIME) on a fixed grid
  std::uint64_t published = 0;
  while (published + timer.skipped_total() < wanted && !hystloop::stop_requested()) {
    const hystloop::TickInfo tick = timer.wait_next();
    const std::size_t n = std::min(sizeof tick.tick, payload.size());
    std::memcpy(payload.data(), &tick.tick, n);  // a sequence number, so datagrams differ
    if (lcm->publish(opt.channel, payload.data(), static_cast<unsigned int>(payload.size())) != 0) {
      std::fprintf(stderr, "hystloop-lcm-fanout: publish on %s failed\n", opt.channel.c_str());
      return 1;
    }
    ++published;
  }
  std::printf("{\"published\": %" PRIu64 ", \"skipped\": %" PRIu64 ", \"cpu_s\": %.6f, \"wall_s\": %.6f}\n", published,
              timer.skipped_total(), cpu_seconds(), seconds_since(start_ns));
  return 0;
}

// Counts what LCM dispatches to the subscription; nothing else on the per-message path.
class Counter {
 public:
  void on_message(const lcm::ReceiveBuffer* /*rbuf*/, const std::string& /*channel*/) noexcept { ++received_; }
  std::uint64_t received() const noexcept { return received_; }

 private:
  std::uint64_t received_ = 0;
};

// Waits up to `timeout_ns` on `fd` (the idle baseline: the stop eventfd, which stays quiet).
void wait_idle(int fd, std::int64_t timeout_ns) noexcept {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(timeout_ns / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(timeout_ns % 1'000'000'000);
  pollfd pfd{fd, POLLIN, 0};
  (void)ppoll(&pfd, 1, &ts, nullptr);
}

int listen(const Options& opt, std::int64_t start_ns) {
  std::unique_ptr<lcm::LCM> lcm;
  Counter counter;
  if (!opt.idle) {
    check_channel(opt.channel);
    // As the services open a channel of the loop: the recommended receive buffer unless the URL sets one.
    lcm = hystloop::open_lcm(hystloop::resolve_lcm_url_for_10khz(opt.url, opt.allow_network), opt.allow_network);
    lcm->subscribe(opt.channel, &Counter::on_message, &counter);
  } else if (!opt.url.empty()) {
    (void)hystloop::checked_lcm_url(opt.url, opt.allow_network);  // refused the same way, though unused
  }

  const std::int64_t end_ns = start_ns + static_cast<std::int64_t>(opt.seconds * 1e9);
  while (!hystloop::stop_requested()) {
    const std::int64_t left_ns = end_ns - monotonic_ns();
    if (left_ns <= 0) break;
    const std::int64_t wait_ns = std::min(left_ns, kMaxWaitNs);
    if (lcm) {
      if (hystloop::handle_pending(*lcm, std::chrono::microseconds(wait_ns / 1000)) < 0) {
        std::fprintf(stderr, "hystloop-lcm-fanout: LCM reported an error while receiving\n");
        return 1;
      }
    } else {
      wait_idle(hystloop::stop_fd(), wait_ns);
    }
  }
  std::printf("{\"received\": %" PRIu64 ", \"cpu_s\": %.6f, \"wall_s\": %.6f}\n", counter.received(), cpu_seconds(),
              seconds_since(start_ns));
  return 0;
}

void add_common(CLI::App& cmd, Options& opt, bool channel_required) {
  cmd.add_option("--url", opt.url,
                 "LCM URL (default: $LCM_DEFAULT_URL, else " + std::string(hystloop::kDefaultLcmUrl) +
                     "); a udpm ttl > 0 or tcpq is refused without --allow-network");
  auto* channel = cmd.add_option("--channel", opt.channel, "Channel name (listen: LCM treats it as a regex)");
  if (channel_required) channel->required();
  cmd.add_option("--seconds", opt.seconds, "Duration [s]")->check(CLI::Range(0.001, 86400.0))->capture_default_str();
  cmd.add_flag("--allow-network", opt.allow_network, "Accept an LCM URL whose packets can leave this host");
}

}  // namespace

int main(int argc, char** argv) try {
  const std::int64_t start_ns = monotonic_ns();
  Options opt;
  CLI::App app{
      "Measures the CPU a process spends on LCM multicast traffic: publish raw payloads, or listen and count."};
  app.require_subcommand(1);

  CLI::App* pub = app.add_subcommand("publish", "Publish raw payloads of --bytes at --rate on a fixed deadline grid");
  add_common(*pub, opt, true);
  pub->add_option("--rate", opt.rate_hz, "Messages per second [Hz]")
      ->check(CLI::Range(0.1, 1e6))
      ->capture_default_str();
  pub->add_option("--bytes", opt.bytes, "Payload size [bytes]")->check(CLI::Range(1, 1'000'000))->capture_default_str();

  CLI::App* sub = app.add_subcommand("listen", "Subscribe to --channel and count the messages dispatched to it");
  add_common(*sub, opt, false);
  auto* idle = sub->add_flag("--idle", opt.idle,
                             "Open no LCM at all: the same wait loop on a file descriptor that stays quiet (baseline)");
  sub->get_option("--channel")->excludes(idle);
  if (const auto exit_code = hystloop::parse_cli(app, argc, argv)) return *exit_code;

  try {
    if (sub->parsed() && !opt.idle && opt.channel.empty()) {
      throw hystloop::ParameterError("channel", "listen needs --channel (or --idle for the baseline)");
    }
    hystloop::install_stop_handlers();
    return pub->parsed() ? publish(opt, start_ns) : listen(opt, start_ns);
  } catch (const hystloop::ParameterError& e) {
    std::fprintf(stderr, "hystloop-lcm-fanout: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hystloop-lcm-fanout: %s\n", e.what());
    return 1;
  }
} catch (...) {  // CLI11's set-up and what the handler above does not take: nothing escapes main
  return hystloop::exit_on_escaped_exception("hystloop-lcm-fanout");
}
