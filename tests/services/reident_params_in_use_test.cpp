// ParamsInUse: which set candidates are judged against, the versions we publish, and the
// version the compensator applies at a sample (HX_COMMAND, planned ahead of the samples).
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

// Commands for ticks first .. last with one version, as one or more HX_COMMAND blocks carry them.
void command_ticks(ParamsInUse& p, std::int64_t first, std::int64_t last, std::int32_t version) {
  for (std::int64_t s = first; s <= last; ++s) p.on_command(s, version);
}

TEST(ParamsInUse, TheAppliedVersionIsUnknownUntilACommandForTheTickOrBefore) {
  ParamsInUse p(kConfig, "reident@a");
  EXPECT_EQ(p.applied_version(), ParamsInUse::kUnknownVersion);
  EXPECT_EQ(p.on_sample(0), ParamsInUse::kUnknownVersion);  // no compensator yet
  command_ticks(p, 10, 19, 1);
  EXPECT_EQ(p.on_sample(5), ParamsInUse::kUnknownVersion);
  EXPECT_EQ(p.on_sample(10), 1);
  EXPECT_EQ(p.applied_version(), 1);
  EXPECT_EQ(p.on_sample(40), 1);  // late: the bridge held the last command
}

TEST(ParamsInUse, TheAppliedVersionAtASampleComesFromTheCommandsAtOrBeforeItsTick) {
  ParamsInUse p(kConfig, "reident@a");
  // Commands run ~30 ms (300 ticks) ahead; the compensator swaps to version 2 at tick 250.
  command_ticks(p, 0, 249, 1);
  command_ticks(p, 250, 299, 2);
  EXPECT_EQ(p.on_sample(100), 1);  // the last block received says 2: not applied yet
  EXPECT_EQ(p.on_sample(249), 1);
  EXPECT_EQ(p.on_sample(250), 2);
  command_ticks(p, 300, 599, 2);
  EXPECT_EQ(p.on_sample(260), 2);
  EXPECT_EQ(p.applied_version(), 2);
  EXPECT_EQ(p.version(), 1);  // the set candidates are judged against is not changed by commands
  EXPECT_EQ(p.command_versions_dropped(), 0u);
}

TEST(ParamsInUse, VersionsTheCompensatorAppliesAreNumberedAbove) {
  // Started after version 9 was published (or restarted after publishing it): HX_PARAMS
  // does not repeat it, the commands carry it. Our next set must be above it.
  ParamsInUse p(kConfig, "reident@a");
  command_ticks(p, 0, 99, 9);
  EXPECT_EQ(p.highest_seen(), 9);
  EXPECT_EQ(p.version(), 1);
  EXPECT_EQ(p.adopt_own(kOther), 10);
  // Our own set, applied later, is not above anything.
  command_ticks(p, 100, 199, 10);
  EXPECT_EQ(p.claim_version(), 11);
  EXPECT_EQ(p.offer(kOther, 10, true, "reident@a"), ParamsOffer::echo);
}

}  // namespace
}  // namespace hystloop
