// SwapReview on made-up errors: its spans' closed forms, the two windows and the rule, and every
// way a review ends without a verdict.
#include "loop/swap_review.hpp"

#include "loop/parameter_exchange.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "support/refusal.hpp"

namespace hystloop {
namespace {

constexpr double kDt = 1e-4;
constexpr std::int64_t kHorizon = 500;
constexpr std::int64_t kRamp = 200;

TEST(SwapReviewSpan, CoversTwoPeriodsAndATenthOfASecondAndSettlesPastTheReanchoring) {
  // 100 Hz: 10 periods each side; settling 10 ms + 50 ms + 20 ms + 20 ms = 100 ms, 10 periods.
  SwapReviewSpan s = swap_review_span(0.01, kDt, kHorizon, kRamp);
  EXPECT_EQ(s.window_ticks, 1000);
  EXPECT_EQ(s.settle_ticks, 1000);
  // 10 Hz: two periods; settling 190 ms rounded up to two periods.
  s = swap_review_span(0.1, kDt, kHorizon, kRamp);
  EXPECT_EQ(s.window_ticks, 2000);
  EXPECT_EQ(s.settle_ticks, 2000);
  s = swap_review_span(1.0 / 0.7, kDt, kHorizon, kRamp);
  EXPECT_EQ(s.window_ticks, 0);                     // slower than kMaxWindow_s a period: not judged
  s = swap_review_span(0.8, kDt, kHorizon, kRamp);  // one period; settling 0.89 s, two periods
  EXPECT_EQ(s.window_ticks, 8000);
  EXPECT_EQ(s.settle_ticks, 16000);
  EXPECT_EQ(swap_review_span(0.0, kDt, kHorizon, kRamp).window_ticks, 0);
}

TEST(SwapReviewConfig, RefusesARatioThatJudgesNoiseOrNothingNamingTheField) {
  SwapReviewConfig c;
  EXPECT_NO_THROW(c.validate());
  c.worse_ratio = 0.0;  // off
  EXPECT_NO_THROW(c.validate());
  c.worse_ratio = 1.01;
  EXPECT_EQ(testing::refused_field([&] { c.validate(); }), "compensator.swap_worse_ratio");
  c.worse_ratio = 1.5;
  c.min_excess_m = -1e-9;
  EXPECT_EQ(testing::refused_field([&] { c.validate(); }), "compensator.swap_min_excess_m");
}

// A rig of its own: ticks planned kHorizon ahead of the samples, the error of each sample given.
class Rig {
 public:
  explicit Rig(SwapReviewConfig config = {}) : review_(config, 10001, kHorizon) {}

  // Plans through tick k + kHorizon (comparable or not) and observes tick k with error e_m.
  SwapReview::Verdict step(double e_m, bool comparable = true) {
    while (planned_ <= k_ + kHorizon) {
      review_.planned(planned_, 0.0, comparable);
      ++planned_;
    }
    return review_.observe(k_++, e_m);
  }
  // Runs n ticks of error alternating +-e_m (RMS e_m); the last verdict other than none.
  SwapReview::Verdict run(std::int64_t n, double e_m) {
    SwapReview::Verdict v = SwapReview::Verdict::none;
    for (std::int64_t i = 0; i < n; ++i) {
      const SwapReview::Verdict now = step(k_ % 2 == 0 ? e_m : -e_m);
      if (now != SwapReview::Verdict::none) v = now;
    }
    return v;
  }
  // A swap at the next tick planned.
  bool swap(SwapReviewSpan span = {1000, 1000}, bool judge = true) { return review_.swapped(planned_, span, judge); }
  std::int64_t next_planned() const { return planned_; }
  SwapReview& review() { return review_; }

 private:
  SwapReview review_;
  std::int64_t k_ = 0;
  std::int64_t planned_ = 0;
};

TEST(SwapReview, TakesBackASwapWorseByTheRatioAndTheExcessAndKeepsTheRest) {
  struct Case {
    double before_m, after_m;
    SwapReview::Verdict verdict;
  };
  for (const Case c : {Case{2e-9, 3.1e-9, SwapReview::Verdict::worse},   // 1.55 x, 1.1 nm more
                       Case{2e-9, 2.9e-9, SwapReview::Verdict::kept},    // 1.45 x
                       Case{0.4e-9, 0.8e-9, SwapReview::Verdict::kept},  // 2 x, but 0.4 nm: the noise's share
                       Case{2e-9, 0.5e-9, SwapReview::Verdict::kept}}) {
    Rig rig;
    rig.run(3000, c.before_m);
    const std::int64_t swap_tick = rig.next_planned();
    ASSERT_TRUE(rig.swap());
    EXPECT_TRUE(rig.review().reviewing());
    // The plan's lead, then the settling (an error there is not judged), then the window.
    rig.run(swap_tick - 3000, c.before_m);
    rig.run(1000, 50e-9);
    const SwapReview::Verdict v = rig.run(1000, c.after_m);
    EXPECT_EQ(v, c.verdict) << c.before_m << " -> " << c.after_m;
    EXPECT_NEAR(rig.review().before_rms_m(), c.before_m, 1e-15);
    EXPECT_NEAR(rig.review().after_rms_m(), c.after_m, 1e-15);
    EXPECT_FALSE(rig.review().reviewing());
  }
}

TEST(SwapReview, JudgesNothingWithoutAComparableWindowOnEitherSide) {
  {  // Too early: the window before reaches back before the first tick planned.
    Rig rig;
    rig.run(100, 1e-9);
    EXPECT_FALSE(rig.swap());
  }
  {  // Off: worse_ratio 0.
    SwapReviewConfig off;
    off.worse_ratio = 0.0;
    Rig rig(off);
    rig.run(3000, 1e-9);
    EXPECT_FALSE(rig.swap());
  }
  {  // Asked not to (a take-back): and the next swap's window may not reach across its settling.
    Rig rig;
    rig.run(3000, 1e-9);
    EXPECT_FALSE(rig.swap({1000, 1000}, /*judge=*/false));
    rig.run(1500, 1e-9);
    EXPECT_FALSE(rig.swap());  // its window before is inside the first's settling
    rig.run(3000, 1e-9);
    EXPECT_TRUE(rig.swap());
  }
  {  // A tick planned that is not comparable (a new reference, learning) ends the review.
    Rig rig;
    rig.run(3000, 1e-9);
    ASSERT_TRUE(rig.swap());
    rig.step(1e-9, /*comparable=*/false);
    EXPECT_FALSE(rig.review().reviewing());
    EXPECT_EQ(rig.run(3000, 9e-9), SwapReview::Verdict::none);
  }
  {  // Samples missing from the window after: no verdict (with them all, the same errors are one).
    for (const std::int64_t stride : {1, 3}) {
      SwapReview review({}, 10001, kHorizon);
      std::int64_t planned = 0;
      const auto plan_to = [&](std::int64_t k) {
        for (; planned <= k + kHorizon; ++planned) review.planned(planned, 0.0, true);
      };
      for (std::int64_t k = 0; k < 2500; ++k) {
        plan_to(k);
        review.observe(k, 1e-9);
      }
      ASSERT_TRUE(review.swapped(planned, {1000, 1000}));
      const std::int64_t swap = planned;
      SwapReview::Verdict v = SwapReview::Verdict::none;
      for (std::int64_t k = 2500; k < swap + 2100; ++k) {
        plan_to(k);
        const bool after = k >= swap;
        if (after && (k - swap) % stride != 0) continue;  // stride 3: two in three missing after the swap
        if (const auto now = review.observe(k, after ? 9e-9 : 1e-9); now != SwapReview::Verdict::none) v = now;
      }
      EXPECT_EQ(v, stride == 1 ? SwapReview::Verdict::worse : SwapReview::Verdict::none) << stride;
      EXPECT_FALSE(review.reviewing());
    }
  }
}

// A take-back travels with its set: a newer set offered in its place is an ordinary one (judged),
// and a mode set by hand drops a take-back waiting, never an ordinary set.
TEST(ParameterExchangeTakeBack, ANewerSetReplacesATakeBackAndOnlyATakeBackIsDropped) {
  ParameterExchange x{CompensatorConfig{}};
  ModelParamSet set;
  set.kind = ModelKind::pi;
  x.offer(set, true, 3, /*take_back=*/true);
  ASSERT_TRUE(x.has_pending());
  EXPECT_TRUE(x.pending().take_back);
  x.offer(set, true, 9);
  EXPECT_FALSE(x.pending().take_back);
  x.drop_take_back();
  EXPECT_TRUE(x.has_pending());  // an ordinary set stays
  x.offer(set, true, 3, /*take_back=*/true);
  x.drop_take_back();
  EXPECT_FALSE(x.has_pending());
}

TEST(SwapReview, CancelEndsAReviewAndNoLaterWindowReachesBackAcrossIt) {
  Rig rig;
  rig.run(3000, 1e-9);
  ASSERT_TRUE(rig.swap());
  rig.review().cancel();
  EXPECT_FALSE(rig.review().reviewing());
  EXPECT_EQ(rig.run(3000, 9e-9), SwapReview::Verdict::none);
  EXPECT_TRUE(rig.swap());  // 3000 ticks later: the window before lies after the cancel
  rig.run(200, 1e-9);
  rig.review().cancel();
  rig.run(500, 1e-9);
  EXPECT_FALSE(rig.swap());  // its window before would reach back across the cancel
}

}  // namespace
}  // namespace hystloop
