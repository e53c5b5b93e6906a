// hystloop-timer-check: runs hystloop::PeriodicTimer at a given rate and prints
// how late it woke (p50/p99/p99.9/max in µs) and how many ticks it skipped, to
// judge whether a machine can hold the bridge's 10 kHz clock.
//
//   hystloop-timer-check --rate 10000 --seconds 1 [--rt-priority 80] [--cpu 1] [--lock-memory]

#include <CLI/CLI.hpp>

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <optional>

#include "core/cli.hpp"
#include "core/logging.hpp"
#include "core/periodic_timer.hpp"
#include "core/process.hpp"

namespace {

struct Options {
  double rate_hz = 10'000.0;
  double seconds = 1.0;
  std::optional<int> rt_priority;
  std::optional<int> cpu;
  bool lock_memory = false;
  bool check = false;
};

struct Result {
  std::uint64_t deadlines = 0;  // deadlines that came due: served + skipped
  std::uint64_t served = 0;
  std::uint64_t skipped = 0;
  double elapsed_s = 0;
  std::int64_t worst_overdue_ns = 0;  // wake - first deadline missed (lateness + skipped * period)
  hystloop::LatencyStats::Summary lateness;
};

// Ticks of `period` [ns] until `wanted` deadlines came due (or a stop signal).
Result run(std::int64_t period, std::uint64_t wanted) {
  hystloop::PeriodicTimer timer(period);
  const std::int64_t start = hystloop::monotonic_ns();
  Result r;
  hystloop::TickInfo t;
  do {
    t = timer.wait_next();
    const auto overdue = t.lateness_ns + static_cast<std::int64_t>(t.skipped) * period;
    if (overdue > r.worst_overdue_ns) r.worst_overdue_ns = overdue;
  } while (t.tick + 1 < wanted && !hystloop::stop_requested());
  r.elapsed_s = 1e-9 * static_cast<double>(hystloop::monotonic_ns() - start);
  r.served = timer.ticks_served();
  r.skipped = timer.skipped_total();
  r.deadlines = t.tick + 1;
  r.lateness = timer.lateness_stats().summary();
  return r;
}

// With --check: the result is consistent (not: fast). Exit code 1 otherwise.
bool consistent(const Result& r, std::uint64_t wanted) {
  const auto& l = r.lateness;
  return r.served + r.skipped == r.deadlines && r.deadlines >= wanted && l.count == r.served && l.min_ns >= 0 &&
         l.p50_ns <= l.p99_ns && l.p99_ns <= l.p999_ns && l.p999_ns <= l.max_ns;
}

// The whole run: parse, set up, tick, print. What it throws run_tool prints; a refused set-up
// (set_cpu_affinity's ParameterError) exits 2, any other failure 1.
int run_timer_check(int argc, char** argv) {
  Options opt;
  CLI::App app{"Runs the hystloop periodic timer and reports its wake-up lateness and missed ticks."};
  app.add_option("--rate", opt.rate_hz, "Tick rate [Hz]")->check(CLI::Range(0.1, 1e6))->capture_default_str();
  app.add_option("--seconds", opt.seconds, "Duration [s]")->check(CLI::Range(0.001, 86400.0))->capture_default_str();
  app.add_option("--rt-priority", opt.rt_priority, "Run SCHED_FIFO at this priority (1..99; non-fatal if refused)")
      ->check(CLI::Range(1, 99));
  app.add_option("--cpu", opt.cpu, "Pin to this CPU (non-fatal if refused)")->check(CLI::NonNegativeNumber);
  app.add_flag("--lock-memory", opt.lock_memory, "mlockall before running (non-fatal if refused)");
  app.add_flag("--check", opt.check, "Exit 1 unless every deadline is accounted for and the percentiles are ordered");
  if (const auto exit_code = hystloop::parse_cli(app, argc, argv)) return *exit_code;

  hystloop::init_logging("timer-check", "info");
  hystloop::install_stop_handlers();
  if (opt.lock_memory) hystloop::lock_memory();
  if (opt.cpu) hystloop::set_cpu_affinity({*opt.cpu});
  if (opt.rt_priority) hystloop::set_realtime_priority(*opt.rt_priority);

  const std::int64_t period = hystloop::period_ns_from_rate_hz(opt.rate_hz);
  const auto wanted = static_cast<std::uint64_t>(std::llround(opt.seconds * 1e9 / static_cast<double>(period)));
  const Result r = run(period, wanted);
  const auto& l = r.lateness;
  const auto usage = hystloop::read_resource_usage();

  std::printf("rate %.0f Hz (period %" PRId64 " ns), %.3f s\n", opt.rate_hz, period, r.elapsed_s);
  std::printf("deadlines %" PRIu64 ": served %" PRIu64 ", skipped %" PRIu64 " (%.3f %%)\n", r.deadlines, r.served,
              r.skipped, r.deadlines ? 100.0 * static_cast<double>(r.skipped) / static_cast<double>(r.deadlines) : 0.0);
  std::printf("lateness [us]: p50 %.1f  p99 %.1f  p99.9 %.1f  max %.1f  mean %.1f\n", l.p50_ns / 1e3, l.p99_ns / 1e3,
              l.p999_ns / 1e3, l.max_ns / 1e3, l.mean_ns / 1e3);
  std::printf("worst overrun: %.1f us after the first deadline it missed\n",
              static_cast<double>(r.worst_overdue_ns) / 1e3);
  std::printf("cpu %.3f s user + %.3f s system, peak rss %.1f MiB, involuntary switches %" PRId64 "\n",
              usage.user_cpu_s, usage.system_cpu_s, static_cast<double>(usage.peak_rss_bytes) / (1 << 20),
              usage.involuntary_switches);
  if (hystloop::stop_requested()) {
    std::printf("stopped early by signal\n");
    return 130;
  }
  if (opt.check && !consistent(r, wanted)) {
    std::printf("check FAILED: deadlines not accounted for or percentiles out of order\n");
    return 1;
  }
  if (opt.check) std::printf("check passed\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return hystloop::run_tool("hystloop-timer-check", [&] { return run_timer_check(argc, argv); });
}
