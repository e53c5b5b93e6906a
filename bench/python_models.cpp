// hystloop-bench-models: the C++ side of bench/python-models. Runs hystloop-model's loop
// (tools/model's ModelRun::forward / inverse, the loop hystloop.Model copies) over N samples in
// memory for every model of the registry with its default parameters, R times each, and prints
// one line per model and direction: "<model> <forward|inverse> <median seconds>".
//
//   hystloop-bench-models [SAMPLES] [RUNS]      (defaults 1000000, 7)
//
// The input: t = k * 1e-4 s, u = 100 sin(2 pi 10 t) V (ten loops a second of 10 kHz samples);
// the inverse is run on the forward's output.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "model_registry.hpp"

namespace {

using Clock = std::chrono::steady_clock;

template <class F>
double median_seconds(int runs, F&& run) {
  std::vector<double> times;
  for (int r = 0; r < runs; ++r) {
    const auto start = Clock::now();
    run();
    times.push_back(std::chrono::duration<double>(Clock::now() - start).count());
  }
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const std::size_t n = argc > 1 ? std::stoul(argv[1]) : 1'000'000;
  const int runs = argc > 2 ? std::stoi(argv[2]) : 7;
  if (n < 2 || runs < 1) {
    std::fprintf(stderr, "usage: hystloop-bench-models [SAMPLES >= 2] [RUNS >= 1]\n");
    return 2;
  }
  std::vector<double> t(n), u(n);
  for (std::size_t k = 0; k < n; ++k) {
    t[k] = static_cast<double>(k) * 1e-4;
    u[k] = 100.0 * std::sin(2.0 * std::numbers::pi * 10.0 * t[k]);
  }
  double sink = 0.0;  // the results are used: the loops are not optimised away
  for (const hystloop::model_tool::ModelEntry* entry : hystloop::model_tool::model_registry()) {
    const auto model = entry->configure({});
    std::vector<double> y;
    const double fwd = median_seconds(runs, [&] {
      y = model->forward(t, u);
      sink += y.back();
    });
    std::printf("%s forward %.9g\n", std::string(entry->name).c_str(), fwd);
    if (entry->has_inverse) {
      const double inv = median_seconds(runs, [&] { sink += model->inverse(t, y).back(); });
      std::printf("%s inverse %.9g\n", std::string(entry->name).c_str(), inv);
    }
  }
  std::fprintf(stderr, "(checksum %g)\n", sink);
  return 0;
}
