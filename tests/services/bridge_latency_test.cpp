// hystloop-bridge --latency-test: the verdict a lab reads before arming, and the histogram it
// reads it from (bridge/latency_test.hpp). The run itself: tests/hw/comedi_probe_test.cpp.
#include "bridge/latency_test.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "support/text.hpp"

namespace hystloop {
namespace {

using testing::contains;

LatencyStats of(std::initializer_list<std::int64_t> ns, int times = 1) {
  LatencyStats s;
  for (int i = 0; i < times; ++i) {
    for (const std::int64_t v : ns) s.add(v);
  }
  return s;
}

TEST(LatencyTest, AHostIsFitToArmOnlyWithoutSkippedTicksAndWithAP99WithinATenthOfTheTick) {
  const LatencyStats quiet = of({2'000, 3'000, 4'000, 9'000}, 100);  // p99 9 us, the bound at 10 kHz 10 us
  EXPECT_TRUE(judge_latency(quiet, 0, 1e4).fit) << judge_latency(quiet, 0, 1e4).reason;
  const LatencyVerdict skipped = judge_latency(quiet, 3, 1e4);
  EXPECT_FALSE(skipped.fit);
  EXPECT_TRUE(contains(skipped.reason, "3 tick(s) skipped")) << skipped.reason;
  LatencyStats tail = of({2'000}, 97);
  for (int i = 0; i < 3; ++i) tail.add(50'000);  // 3 % at 50 us: p99 50 us
  const LatencyVerdict late = judge_latency(tail, 0, 1e4);
  EXPECT_FALSE(late.fit);
  EXPECT_TRUE(contains(late.reason, "p99 50.0 us beyond a tenth of the tick (10.0 us)")) << late.reason;
  EXPECT_TRUE(judge_latency(tail, 0, 1e3).fit);  // at 1 kHz the bound is 100 us
  EXPECT_FALSE(judge_latency(LatencyStats{}, 0, 1e4).fit);
}

TEST(LatencyTest, TheHistogramCountsEverySampleInItsBin) {
  const LatencyStats s = of({500, 1'500, 1'600, 7'000, 150'000, 20'000'000});
  char* text = nullptr;
  std::size_t size = 0;
  std::FILE* out = ::open_memstream(&text, &size);
  print_latency_histogram(s, out);
  std::fclose(out);
  const std::string h(text, size);
  std::free(text);
  std::istringstream lines(h);
  std::string line;
  std::uint64_t total = 0;
  std::vector<std::uint64_t> counts;
  while (std::getline(lines, line)) {  // the count: the last field but the bar of #
    std::istringstream row(line);
    std::vector<std::string> fields;
    for (std::string f; row >> f;) {
      if (f.find_first_not_of('#') != std::string::npos) fields.push_back(f);
    }
    ASSERT_FALSE(fields.empty()) << h;
    const std::uint64_t n = std::stoull(fields.back());
    counts.push_back(n);
    total += n;
  }
  EXPECT_EQ(total, 6u) << h;
  ASSERT_EQ(counts.size(), 13u) << h;
  EXPECT_EQ(counts[0], 1u) << h;   // 0 .. 1 us: 0.5 us
  EXPECT_EQ(counts[1], 2u) << h;   // 1 .. 2 us: 1.5, 1.6 us
  EXPECT_EQ(counts[3], 1u) << h;   // 5 .. 10 us: 7 us
  EXPECT_EQ(counts[7], 1u) << h;   // 100 .. 200 us: 150 us
  EXPECT_EQ(counts[12], 1u) << h;  // beyond 10 ms: 20 ms
}

}  // namespace
}  // namespace hystloop
