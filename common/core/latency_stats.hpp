#pragma once
// Fixed-size log-linear histogram of durations (nanoseconds), HDR-like: exact
// below 128 ns, then 128 sub-buckets per power of two, so a bucket is at most
// 1/128 (0.78 %) of its value wide. A percentile is reported as the middle of its
// bucket, clamped to the exact min/max: the relative error is <= 1/256 (0.4 %),
// or +-0.5 ns below 128 ns. Range 0 .. 2^34 ns (~17 s); longer durations are
// counted in the top bucket (overflow_count()), and min/max/mean stay exact.
//
// add() is O(1), noexcept, allocates nothing and locks nothing: it may sit on a
// per-sample path. percentile() walks the buckets (~3.6k): call it once a second
// for a status report, not per sample. Not thread-safe: one writer; hand a copy
// (or merge()) to whoever reports.

#include <array>
#include <cstdint>

namespace hystloop {

class LatencyStats {
 public:
  static constexpr int kSubBucketBits = 7;  // 128 sub-buckets per octave
  static constexpr int kMaxValueBits = 34;  // values < 2^34 ns are binned exactly
  static constexpr std::int64_t kMaxTrackableNs = (std::int64_t{1} << kMaxValueBits) - 1;
  static constexpr std::size_t kBucketCount =
      (std::size_t{1} << kSubBucketBits) * static_cast<std::size_t>(kMaxValueBits - kSubBucketBits + 1);

  // Records one duration. Negative durations are recorded as 0 (a clock that
  // wakes early is not a latency); see clamped_negative_count().
  void add(std::int64_t ns) noexcept;

  // Adds every sample of `other` (for per-thread or per-window stats).
  void merge(const LatencyStats& other) noexcept;
  // Forgets everything (start of a new reporting window).
  void reset() noexcept;

  std::uint64_t count() const noexcept { return count_; }
  // 0 when empty: check count() first.
  std::int64_t min_ns() const noexcept { return count_ ? min_ : 0; }
  std::int64_t max_ns() const noexcept { return count_ ? max_ : 0; }
  double mean_ns() const noexcept;
  // Nearest-rank percentile for q in [0, 1]: the value of the ceil(q*count)-th
  // smallest sample, to the resolution above; q = 0 gives min, q = 1 gives max.
  // 0 when empty. Throws ParameterError("q") for q outside [0, 1] or NaN.
  double percentile(double q) const;
  // Samples below `ns`, to the buckets' resolution: those in the buckets below the one `ns` falls
  // in (a histogram's bins from it). Walks the buckets, as percentile() does.
  std::uint64_t count_below(std::int64_t ns) const noexcept;

  std::uint64_t overflow_count() const noexcept { return overflow_; }
  std::uint64_t clamped_negative_count() const noexcept { return negative_; }

  // The figures a status message carries, in nanoseconds.
  struct Summary {
    std::uint64_t count = 0;
    double min_ns = 0, p50_ns = 0, p99_ns = 0, p999_ns = 0, max_ns = 0, mean_ns = 0;
  };
  Summary summary() const;

  // Bucket arithmetic, exposed for tests: index of a value and the value range
  // [lowest, highest] that index covers.
  static std::size_t bucket_index(std::int64_t ns) noexcept;
  static std::int64_t bucket_lowest(std::size_t index) noexcept;
  static std::int64_t bucket_highest(std::size_t index) noexcept;

 private:
  std::array<std::uint64_t, kBucketCount> buckets_{};
  std::uint64_t count_ = 0;
  std::uint64_t overflow_ = 0;
  std::uint64_t negative_ = 0;
  std::int64_t sum_ = 0;  // ns; overflows only after ~290 years of summed latency
  std::int64_t min_ = 0;
  std::int64_t max_ = 0;
};

}  // namespace hystloop
