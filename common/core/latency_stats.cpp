#include "core/latency_stats.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

#include "core/errors.hpp"

namespace hystloop {
namespace {
constexpr std::int64_t kSubBuckets = std::int64_t{1} << LatencyStats::kSubBucketBits;
}  // namespace

std::size_t LatencyStats::bucket_index(std::int64_t ns) noexcept {
  if (ns < 0) ns = 0;
  if (ns > kMaxTrackableNs) ns = kMaxTrackableNs;
  if (ns < kSubBuckets) return static_cast<std::size_t>(ns);
  const int octave = static_cast<int>(std::bit_width(static_cast<std::uint64_t>(ns))) - 1;  // floor(log2 ns) >= 7
  const int shift = octave - kSubBucketBits;
  const std::int64_t sub = (ns >> shift) - kSubBuckets;  // 0 .. 127
  return static_cast<std::size_t>(kSubBuckets + shift * kSubBuckets + sub);
}

std::int64_t LatencyStats::bucket_lowest(std::size_t index) noexcept {
  const auto i = static_cast<std::int64_t>(index);
  if (i < kSubBuckets) return i;
  const std::int64_t shift = (i - kSubBuckets) / kSubBuckets;
  const std::int64_t sub = (i - kSubBuckets) % kSubBuckets;
  return (kSubBuckets + sub) << shift;
}

std::int64_t LatencyStats::bucket_highest(std::size_t index) noexcept {
  const auto i = static_cast<std::int64_t>(index);
  if (i < kSubBuckets) return i;
  const std::int64_t shift = (i - kSubBuckets) / kSubBuckets;
  return bucket_lowest(index) + (std::int64_t{1} << shift) - 1;
}

void LatencyStats::add(std::int64_t ns) noexcept {
  if (ns < 0) {
    ++negative_;
    ns = 0;
  }
  if (ns > kMaxTrackableNs) ++overflow_;
  ++buckets_[bucket_index(ns)];
  if (count_ == 0) {
    min_ = max_ = ns;
  } else {
    min_ = std::min(min_, ns);
    max_ = std::max(max_, ns);
  }
  ++count_;
  sum_ += ns;
}

void LatencyStats::merge(const LatencyStats& other) noexcept {
  if (other.count_ == 0) return;
  for (std::size_t i = 0; i < kBucketCount; ++i) buckets_[i] += other.buckets_[i];
  if (count_ == 0) {
    min_ = other.min_;
    max_ = other.max_;
  } else {
    min_ = std::min(min_, other.min_);
    max_ = std::max(max_, other.max_);
  }
  count_ += other.count_;
  overflow_ += other.overflow_;
  negative_ += other.negative_;
  sum_ += other.sum_;
}

void LatencyStats::reset() noexcept { *this = LatencyStats{}; }

double LatencyStats::mean_ns() const noexcept {
  return count_ ? static_cast<double>(sum_) / static_cast<double>(count_) : 0.0;
}

double LatencyStats::percentile(double q) const {
  require_in_range("q", q, 0.0, 1.0);
  if (count_ == 0) return 0.0;
  if (q <= 0.0) return static_cast<double>(min_);
  const auto rank = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_))));
  if (rank >= count_) return static_cast<double>(max_);
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < kBucketCount; ++i) {
    seen += buckets_[i];
    if (seen >= rank) {
      const double mid = 0.5 * static_cast<double>(bucket_lowest(i) + bucket_highest(i));
      return std::clamp(mid, static_cast<double>(min_), static_cast<double>(max_));
    }
  }
  return static_cast<double>(max_);  // unreachable: the buckets hold count_ samples
}

std::uint64_t LatencyStats::count_below(std::int64_t ns) const noexcept {
  if (ns <= 0) return 0;
  const std::size_t end = bucket_index(ns);
  std::uint64_t n = 0;
  for (std::size_t i = 0; i < end; ++i) n += buckets_[i];
  return n;
}

LatencyStats::Summary LatencyStats::summary() const {
  Summary s;
  s.count = count_;
  s.min_ns = static_cast<double>(min_ns());
  s.p50_ns = percentile(0.50);
  s.p99_ns = percentile(0.99);
  s.p999_ns = percentile(0.999);
  s.max_ns = static_cast<double>(max_ns());
  s.mean_ns = mean_ns();
  return s;
}

}  // namespace hystloop
