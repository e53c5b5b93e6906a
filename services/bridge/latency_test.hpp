#pragma once
// hystloop-bridge --latency-test SECONDS: what a lab runs on its host, with its card, before it
// arms a stage. The bridge's real-time thread runs the backend's real tick (the card's write and
// read) for SECONDS, never armed: every output holds its safe voltage throughout. No LCM. Prints a
// progress line a second, then the timer's wake-up lateness and the tick's work as percentiles and
// a histogram, the ticks skipped, and a verdict: fit to arm when no tick was skipped and the
// lateness p99 is within a tenth of the tick (docs/TIMING.md, "Real-time host").

#include <cstdio>

#include "bridge/bridge_settings.hpp"
#include "core/latency_stats.hpp"

namespace hystloop {

struct LatencyVerdict {
  bool fit = false;
  std::string reason;  // why (the figure that decided it)
};

// The verdict on a run's figures: a skipped tick, or a lateness p99 beyond a tenth of the tick,
// is a host to fix before arming.
LatencyVerdict judge_latency(const LatencyStats& lateness, std::uint64_t ticks_skipped, double rate_hz);

// The histogram's rows: "   5 us ..  10 us  12345  ######" for fixed bins from 1 us to 10 ms.
void print_latency_histogram(const LatencyStats& stats, std::FILE* out);

// Runs the test. Returns 0 (fit to arm), 1 (not fit, or the backend failed; why on `out`).
int run_latency_test(const BridgeSettings& settings, double seconds, std::FILE* out);

}  // namespace hystloop
