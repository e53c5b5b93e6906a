#include "bridge/latency_test.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <thread>

#include "bridge/bridge_realtime.hpp"
#include "bridge/stage_backend.hpp"

namespace hystloop {
namespace {

// Bin edges [ns]: 1-2-5 steps from 1 us to 10 ms (a 10 kHz tick is 100 us).
constexpr std::array<std::int64_t, 13> kEdgesNs = {0,       1'000,   2'000,   5'000,     10'000,    20'000,    50'000,
                                                   100'000, 200'000, 500'000, 1'000'000, 2'000'000, 10'000'000};

std::string us(double ns) { return fmt::format("{:.1f} us", ns * 1e-3); }

}  // namespace

LatencyVerdict judge_latency(const LatencyStats& lateness, std::uint64_t ticks_skipped, double rate_hz) {
  const double bound_ns = 0.1 / rate_hz * 1e9;
  if (lateness.count() == 0) return {false, "no tick ran"};
  if (ticks_skipped > 0) {
    return {false, fmt::format("{} tick(s) skipped: the outputs held stale voltages while the thread was late",
                               ticks_skipped)};
  }
  const double p99 = lateness.percentile(0.99);
  if (p99 > bound_ns) {
    return {false, fmt::format("wake-up lateness p99 {} beyond a tenth of the tick ({})", us(p99), us(bound_ns))};
  }
  return {true, fmt::format("no tick skipped, wake-up lateness p99 {} within a tenth of the tick ({})", us(p99),
                            us(bound_ns))};
}

void print_latency_histogram(const LatencyStats& stats, std::FILE* out) {
  std::array<std::uint64_t, kEdgesNs.size()> in_bin{};
  for (std::size_t i = 1; i < kEdgesNs.size(); ++i) {
    in_bin[i] = stats.count_below(kEdgesNs[i]) - stats.count_below(kEdgesNs[i - 1]);
  }
  const std::uint64_t beyond = stats.count() - stats.count_below(kEdgesNs.back());
  const std::uint64_t most = std::max(beyond, *std::max_element(in_bin.begin(), in_bin.end()));
  const auto bar = [&](std::uint64_t n) {
    const int width =
        most == 0 ? 0 : static_cast<int>(std::ceil(40.0 * static_cast<double>(n) / static_cast<double>(most)));
    return std::string(static_cast<std::size_t>(n == 0 ? 0 : std::max(width, 1)), '#');
  };
  for (std::size_t i = 1; i < kEdgesNs.size(); ++i) {
    std::fprintf(out, "  %9s .. %9s  %10llu  %s\n", us(static_cast<double>(kEdgesNs[i - 1])).c_str(),
                 us(static_cast<double>(kEdgesNs[i])).c_str(), static_cast<unsigned long long>(in_bin[i]),
                 bar(in_bin[i]).c_str());
  }
  std::fprintf(out, "  %9s .. %9s  %10llu  %s\n", us(static_cast<double>(kEdgesNs.back())).c_str(), "longer",
               static_cast<unsigned long long>(beyond), bar(beyond).c_str());
}

int run_latency_test(const BridgeSettings& settings, double seconds, std::FILE* out) {
  BridgeSettings s = settings;
  s.auto_arm = false;  // never armed: every output at its safe voltage
  BridgeRealtime rt(s, make_stage_backend(s));
  const std::string cpu = s.rt.cpu >= 0 ? fmt::format(", CPU {}", s.rt.cpu) : std::string();
  std::fprintf(out,
               "latency test: %s backend, %g Hz, %g s, outputs held at their safe voltages; the clock thread at "
               "priority %d%s\n",
               s.backend.c_str(), s.rate_hz, seconds, s.rt.priority, cpu.c_str());
  rt.start();
  while (!rt.started()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  std::fprintf(out, "real-time thread: %s; %s\n", rt.priority_status().detail.c_str(),
               rt.affinity_status().detail.c_str());
  LatencyStats lateness, work;
  std::uint64_t skipped = 0;
  const auto begin = std::chrono::steady_clock::now();
  auto next_report = begin + std::chrono::seconds(1);
  bool asked = false;
  const auto collect = [&](bool progress) {
    if (!asked) {
      rt.reports().request();
      asked = true;
    }
    if (const RtReport* r = rt.reports().take()) {
      lateness.merge(r->lateness);
      work.merge(r->work);
      skipped = r->ticks_skipped;
      rt.reports().release();
      asked = false;
      if (progress) {
        const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
        std::fprintf(out, "  %4.0f s: %llu wake-ups, lateness p99 %s max %s, %llu ticks skipped\n", elapsed,
                     static_cast<unsigned long long>(lateness.count()), us(lateness.percentile(0.99)).c_str(),
                     us(static_cast<double>(lateness.max_ns())).c_str(), static_cast<unsigned long long>(skipped));
        std::fflush(out);
      }
      return true;
    }
    return false;
  };
  const auto end = begin + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) {
    while (rt.pop_tick()) {
    }
    if (std::chrono::steady_clock::now() >= next_report) {
      if (collect(true)) next_report += std::chrono::seconds(1);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  for (int i = 0; i < 200 && !collect(false); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  const SafeStopResult stop = rt.stop();
  std::fprintf(out,
               "\ntimer wake-up lateness over %llu wake-ups (%d tick(s) each): p50 %s, p90 %s, p99 %s, p99.9 %s, "
               "max %s\n",
               static_cast<unsigned long long>(lateness.count()), s.rt.ticks_per_wake,
               us(lateness.percentile(0.5)).c_str(), us(lateness.percentile(0.9)).c_str(),
               us(lateness.percentile(0.99)).c_str(), us(lateness.percentile(0.999)).c_str(),
               us(static_cast<double>(lateness.max_ns())).c_str());
  print_latency_histogram(lateness, out);
  std::fprintf(out, "tick work (the card's write and read, the bookkeeping): p50 %s, p99 %s, max %s\n",
               us(work.percentile(0.5)).c_str(), us(work.percentile(0.99)).c_str(),
               us(static_cast<double>(work.max_ns())).c_str());
  std::fprintf(out, "ticks skipped: %llu\n", static_cast<unsigned long long>(skipped));
  if (!stop.reached) std::fprintf(out, "the outputs were told to hold their safe voltages (the stop timed out)\n");
  LatencyVerdict v = judge_latency(lateness, skipped, s.rate_hz);
  if (s.rt.required && !rt.priority_status().ok) v = {false, real_time_refused(rt.priority_status().detail)};
  std::fprintf(out, "verdict: %s: %s%s\n", v.fit ? "fit to arm" : "NOT fit to arm", v.reason.c_str(),
               rt.backend().simulated() ? " (a simulated stage runs late ticks late instead of skipping them: the "
                                          "verdict is a card's host's)"
                                        : "");
  return v.fit ? 0 : 1;
}

}  // namespace hystloop
