#include "core/latency_stats.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "core/errors.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

// The same nearest-rank definition LatencyStats documents: the ceil(q*n)-th smallest.
double exact_percentile(const std::vector<std::int64_t>& sorted, double q) {
  if (q <= 0.0) return static_cast<double>(sorted.front());
  const auto n = sorted.size();
  auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(n)));
  rank = std::clamp<std::size_t>(rank, 1, n);
  return static_cast<double>(sorted[rank - 1]);
}

// Stated resolution: 1/256 of the value (half a bucket), and exact below 128 ns.
double tolerance(double exact) { return std::max(0.5, exact / 256.0); }

TEST(LatencyStats, EmptyReportsZeros) {
  const LatencyStats s;
  EXPECT_EQ(s.count(), 0u);
  EXPECT_EQ(s.min_ns(), 0);
  EXPECT_EQ(s.max_ns(), 0);
  EXPECT_EQ(s.mean_ns(), 0.0);
  EXPECT_EQ(s.percentile(0.5), 0.0);
}

TEST(LatencyStats, BucketsCoverTheRangeContiguouslyWithinOnePercent) {
  for (std::size_t i = 0; i + 1 < LatencyStats::kBucketCount; ++i) {
    ASSERT_EQ(LatencyStats::bucket_highest(i) + 1, LatencyStats::bucket_lowest(i + 1)) << i;
    const auto lo = static_cast<double>(LatencyStats::bucket_lowest(i));
    const auto width = static_cast<double>(LatencyStats::bucket_highest(i) - LatencyStats::bucket_lowest(i) + 1);
    if (lo < 128.0) {
      ASSERT_EQ(width, 1.0) << i;  // exact: <= 1 % from 100 ns on
    } else {
      ASSERT_LE(width / lo, 1.0 / 128.0 + 1e-12) << i;
    }
    ASSERT_EQ(LatencyStats::bucket_index(LatencyStats::bucket_lowest(i)), i);
    ASSERT_EQ(LatencyStats::bucket_index(LatencyStats::bucket_highest(i)), i);
  }
  EXPECT_EQ(LatencyStats::bucket_highest(LatencyStats::kBucketCount - 1), LatencyStats::kMaxTrackableNs);
  EXPECT_GE(LatencyStats::kMaxTrackableNs, 10'000'000'000);  // >= 10 s
}

TEST(LatencyStats, PercentilesMatchSortedDataWithinResolution) {
  std::mt19937_64 rng(20261129);
  // Log-uniform from 50 ns to 5 s: every octave of the range is exercised.
  std::uniform_real_distribution<double> log_ns(std::log(50.0), std::log(5e9));
  for (int trial = 0; trial < 20; ++trial) {
    const std::size_t n = 1 + rng() % 20'000;
    std::vector<std::int64_t> data(n);
    LatencyStats s;
    for (auto& v : data) {
      v = static_cast<std::int64_t>(std::exp(log_ns(rng)));
      s.add(v);
    }
    std::sort(data.begin(), data.end());
    ASSERT_EQ(s.count(), n);
    EXPECT_EQ(s.min_ns(), data.front());
    EXPECT_EQ(s.max_ns(), data.back());
    for (const double q : {0.0, 0.001, 0.1, 0.25, 0.5, 0.9, 0.99, 0.999, 0.9999, 1.0}) {
      const double exact = exact_percentile(data, q);
      EXPECT_NEAR(s.percentile(q), exact, tolerance(exact)) << "n=" << n << " q=" << q;
    }
    const double q = std::uniform_real_distribution<double>(0.0, 1.0)(rng);
    EXPECT_NEAR(s.percentile(q), exact_percentile(data, q), tolerance(exact_percentile(data, q)));
  }
}

TEST(LatencyStats, SmallValuesAreExact) {
  LatencyStats s;
  for (std::int64_t v = 0; v < 128; ++v) s.add(v);
  for (std::int64_t v = 0; v < 128; ++v) {
    EXPECT_EQ(s.percentile(static_cast<double>(v + 1) / 128.0), static_cast<double>(v));
  }
  EXPECT_DOUBLE_EQ(s.mean_ns(), 63.5);
}

TEST(LatencyStats, PercentilesAreOrdered) {
  std::mt19937_64 rng(7);
  std::exponential_distribution<double> d(1.0 / 20'000.0);
  LatencyStats s;
  for (int i = 0; i < 10'000; ++i) s.add(static_cast<std::int64_t>(d(rng)));
  const auto sum = s.summary();
  EXPECT_LE(sum.min_ns, sum.p50_ns);
  EXPECT_LE(sum.p50_ns, sum.p99_ns);
  EXPECT_LE(sum.p99_ns, sum.p999_ns);
  EXPECT_LE(sum.p999_ns, sum.max_ns);
  EXPECT_NEAR(sum.mean_ns, 20'000.0, 1'000.0);
}

TEST(LatencyStats, MergeEqualsAddingEverything) {
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<std::int64_t> d(0, 3'000'000);
  LatencyStats a, b, all;
  for (int i = 0; i < 5'000; ++i) {
    const auto v = d(rng);
    (i % 3 ? a : b).add(v);
    all.add(v);
  }
  a.merge(b);
  EXPECT_EQ(a.count(), all.count());
  EXPECT_EQ(a.min_ns(), all.min_ns());
  EXPECT_EQ(a.max_ns(), all.max_ns());
  EXPECT_DOUBLE_EQ(a.mean_ns(), all.mean_ns());
  for (const double q : {0.1, 0.5, 0.99, 0.999}) EXPECT_EQ(a.percentile(q), all.percentile(q));

  LatencyStats empty;
  empty.merge(all);
  EXPECT_EQ(empty.min_ns(), all.min_ns());
  all.merge(LatencyStats{});
  EXPECT_EQ(all.count(), a.count());
}

TEST(LatencyStats, ResetStartsANewWindow) {
  LatencyStats s;
  s.add(1'000'000);
  s.add(-5);
  s.reset();
  EXPECT_EQ(s.count(), 0u);
  EXPECT_EQ(s.clamped_negative_count(), 0u);
  s.add(300);
  EXPECT_EQ(s.min_ns(), 300);
  EXPECT_EQ(s.max_ns(), 300);
  EXPECT_EQ(s.percentile(0.5), 300.0);
}

TEST(LatencyStats, NegativeAndHugeValuesAreCountedNotLost) {
  LatencyStats s;
  s.add(-40);
  s.add(std::numeric_limits<std::int64_t>::max() / 4);
  EXPECT_EQ(s.count(), 2u);
  EXPECT_EQ(s.clamped_negative_count(), 1u);
  EXPECT_EQ(s.overflow_count(), 1u);
  EXPECT_EQ(s.min_ns(), 0);
  EXPECT_EQ(s.max_ns(), std::numeric_limits<std::int64_t>::max() / 4);
}

TEST(LatencyStats, CountBelowCountsTheSamplesUnderAnEdge) {
  LatencyStats s;
  for (const std::int64_t ns : {0, 50, 500, 1'500, 1'600, 7'000, 150'000}) s.add(ns);
  EXPECT_EQ(s.count_below(0), 0u);
  EXPECT_EQ(s.count_below(51), 2u);  // exact below 128 ns
  EXPECT_EQ(s.count_below(1'000), 3u);
  EXPECT_EQ(s.count_below(2'000), 5u);
  EXPECT_EQ(s.count_below(100'000), 6u);
  EXPECT_EQ(s.count_below(1'000'000), 7u);
}

TEST(LatencyStats, RefusesQuantileOutsideUnitInterval) {
  LatencyStats s;
  s.add(1);
  EXPECT_THROW((void)s.percentile(1.5), ParameterError);
  EXPECT_THROW((void)s.percentile(-0.1), ParameterError);
  EXPECT_THROW((void)s.percentile(std::nan("")), ParameterError);
}

TEST(LatencyStats, AddAllocatesNothing) {
  LatencyStats s;
  LatencyStats other;
  other.add(5);
  testing::AllocationCounter counter;
  for (std::int64_t i = 0; i < 100'000; ++i) s.add(i * 997);
  s.merge(other);
  (void)s.percentile(0.99);
  s.reset();
  EXPECT_EQ(counter.allocations(), 0u);
}

}  // namespace
}  // namespace hystloop
