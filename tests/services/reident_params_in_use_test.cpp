// ParamsInUse: which set candidates are judged against, and the versions we publish.
#include "reidentifier/params_in_use.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "core/errors.hpp"

namespace hystloop {
namespace {

const MemParams kConfig{5e-9, 1.7e-12, 1.2};
const MemParams kOther{6e-9, 1.0e-12, 1.1};

TEST(ParamsInUse, StartsAtTheConfiguredSetAsVersionOne) {
  ParamsInUse p(kConfig, "reident@a");
  EXPECT_EQ(p.version(), 1);
  EXPECT_EQ(p.source(), "config");
  EXPECT_DOUBLE_EQ(p.params().c1, kConfig.c1);
  EXPECT_THROW(ParamsInUse(MemParams{-1.0, 0.0, 1.0}, "x"), ParameterError);
}

TEST(ParamsInUse, OwnSetsGetTheNextVersionAboveAllSeen) {
  ParamsInUse p(kConfig, "reident@a");
  EXPECT_EQ(p.adopt_own(kOther), 2);
  EXPECT_EQ(p.version(), 2);
  EXPECT_EQ(p.source(), "reident@a");
  // Someone published version 10 as invalid (diagnostic): not in use, but numbering goes above it.
  EXPECT_EQ(p.offer(kConfig, 10, false, "ctl"), ParamsOffer::invalid);
  EXPECT_EQ(p.version(), 2);
  EXPECT_EQ(p.adopt_own(kConfig), 11);
  EXPECT_EQ(p.claim_version(), 12);  // a diagnostic set of ours: in use unchanged
  EXPECT_EQ(p.version(), 11);
}

TEST(ParamsInUse, ANewerValidSetFromSomeoneElseBecomesTheSetInUse) {
  ParamsInUse p(kConfig, "reident@a");
  EXPECT_EQ(p.offer(kOther, 5, true, "identify@b"), ParamsOffer::adopted);
  EXPECT_EQ(p.version(), 5);
  EXPECT_EQ(p.source(), "identify@b");
  EXPECT_DOUBLE_EQ(p.params().c1, kOther.c1);
  EXPECT_EQ(p.offer(kConfig, 5, true, "ctl"), ParamsOffer::stale);   // same version: not newer
  EXPECT_EQ(p.offer(kConfig, 3, true, "ctl"), ParamsOffer::stale);
  EXPECT_DOUBLE_EQ(p.params().c1, kOther.c1);
  EXPECT_EQ(p.adopt_own(kConfig), 6);
}

TEST(ParamsInUse, OurOwnEchoIsIgnoredButASecondReidentifierOnTheHostIsNot) {
  ParamsInUse p(kConfig, "reident@a");
  const std::int32_t v = p.adopt_own(kOther);
  EXPECT_EQ(p.offer(kOther, v, true, "reident@a"), ParamsOffer::echo);
  EXPECT_EQ(p.offer(kOther, 1, true, "reident@a"), ParamsOffer::echo);
  // Same source, a version we never published: another re-identifier on this host.
  EXPECT_EQ(p.offer(kConfig, v + 3, true, "reident@a"), ParamsOffer::adopted);
  EXPECT_EQ(p.version(), v + 3);
}

TEST(ParamsInUse, SetsOutsideTheModelDomainAreNeverInUse) {
  ParamsInUse p(kConfig, "reident@a");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(p.offer(MemParams{0.0, 1e-12, 1.0}, 4, true, "x"), ParamsOffer::invalid);
  EXPECT_EQ(p.offer(MemParams{1e-9, -1e-12, 1.0}, 4, true, "x"), ParamsOffer::invalid);
  EXPECT_EQ(p.offer(MemParams{1e-9, 1e-12, nan}, 4, true, "x"), ParamsOffer::invalid);
  EXPECT_EQ(p.version(), 1);
  EXPECT_EQ(p.highest_seen(), 4);
}

}  // namespace
}  // namespace hystloop
