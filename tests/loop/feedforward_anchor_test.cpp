// FeedforwardAnchor's window (loop/feedforward_anchor.hpp): a whole period of the reference from
// the swap's reversal, so that an error which is no offset averages out; the first ticks of a
// reference without a period in it. The plan runs ahead of the samples, as in the loop.
#include "loop/feedforward_anchor.hpp"

#include <gtest/gtest.h>

#include <cstdint>

namespace hystloop {
namespace {

constexpr std::int64_t kMeasure = 20, kMax = 1001, kLead = 500;  // the compensator's defaults at 10 kHz

FeedforwardAnchor anchor() { return FeedforwardAnchor(kMeasure, kMax, 1, 1.0, 1.0); }

// Plans ticks [0, n) with reversals every `half` ticks (0: none) and observes each kLead ticks
// later with y_measured - y_model = offset + error(k); returns the tick whose sample completed it.
template <class Error>
std::int64_t run(FeedforwardAnchor& a, std::int64_t n, std::int64_t half, double offset, Error error) {
  a.start_measuring(0);
  for (std::int64_t k = 0; k < n + kLead; ++k) {
    if (k < n) a.planned(k, 0.0, 0.0, half > 0 && k > 0 && k % half == 0);
    const std::int64_t seen = k - kLead;
    if (seen >= 0 && a.observe(seen, offset + error(seen), 0.0, k + 1, 1e-8)) return seen;
  }
  return -1;
}

TEST(FeedforwardAnchor, TheOffsetIsMeasuredOverAWholePeriodWhereAnErrorOfEachBranchAveragesOut) {
  FeedforwardAnchor a = anchor();
  // A loop too narrow: +3 nm on the rising branch, -3 nm on the falling one (250 ticks each).
  const auto branch_error = [](std::int64_t k) { return (k / 250) % 2 == 0 ? 3e-9 : -3e-9; };
  EXPECT_EQ(run(a, 2000, 250, 1e-9, branch_error), 499);  // the window ends before the second reversal, at 500
  EXPECT_NEAR(a.y_target(), 1e-9, 1e-18);
  // Over the first 20 ticks the branch's error would have been taken for offset: 4 nm.
}

TEST(FeedforwardAnchor, AReferenceWithoutAPeriodInTheWindowIsMeasuredOverItsFirstTicks) {
  FeedforwardAnchor a = anchor();
  // The first 20 ticks at 2 nm, the rest at 10 nm: the window is cut back to the first 20 once
  // the whole capacity was planned, though later ticks had been observed by then.
  const auto later_error = [](std::int64_t k) { return k < kMeasure ? 0.0 : 8e-9; };
  EXPECT_EQ(run(a, 2000, 0, 2e-9, later_error), kMax - 1 - kLead);
  EXPECT_NEAR(a.y_target(), 2e-9, 1e-18);
}

TEST(FeedforwardAnchor, ALostTickIsLeftOutOfTheMean) {
  FeedforwardAnchor a = anchor();
  a.start_measuring(0);
  for (std::int64_t k = 0; k < 1200; ++k) a.planned(k, 0.0, 0.0, k == 100 || k == 200);
  bool done = false;
  for (std::int64_t k = 0; k < 200 && !done; ++k) {
    if (k == 50) continue;  // never arrived
    done = a.observe(k, 5e-9, 0.0, 1200, 1e-8);
  }
  EXPECT_TRUE(done);
  EXPECT_NEAR(a.y_target(), 5e-9, 1e-18);
}

}  // namespace
}  // namespace hystloop
