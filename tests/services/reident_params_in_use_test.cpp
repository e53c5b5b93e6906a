// ParamsInUse: which set candidates are judged against, the versions we publish, and the
// version the compensator applies at a sample (HX_COMMAND, planned ahead of the samples).
#include "reident/params_in_use.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "core/errors.hpp"

namespace hystloop {
namespace {

const MemParams kConfig{5e-9, 1.7e-12, 1.2};
const MemParams kOther{6e-9, 1.0e-12, 1.1};
constexpr std::int64_t kOwn = 0x4e1d;  // our publisher id
constexpr std::int64_t kCtl = 0xc71;
constexpr std::int64_t kIdentify = 0x1de;

TEST(ParamsInUse, StartsAtTheConfiguredSetAsVersionOne) {
  ParamsInUse p(kConfig, "reident@a", kOwn);
  EXPECT_EQ(p.version(), 1);
  EXPECT_EQ(p.source(), "config");
  EXPECT_DOUBLE_EQ(p.params().c1, kConfig.c1);
  EXPECT_THROW(ParamsInUse(MemParams{-1.0, 0.0, 1.0}, "x", kOwn), ParameterError);
}

TEST(ParamsInUse, OwnSetsGetTheNextVersionAboveAllSeen) {
  ParamsInUse p(kConfig, "reident@a", kOwn);
  EXPECT_EQ(p.adopt_own(kOther), 2);
  EXPECT_EQ(p.version(), 2);
  EXPECT_EQ(p.source(), "reident@a");
  // Someone published version 10 as invalid (diagnostic): not in use, but numbering goes above it.
  EXPECT_EQ(p.offer(kConfig, 10, kCtl, false, "ctl"), ParamsOffer::invalid);
  EXPECT_EQ(p.version(), 2);
  EXPECT_EQ(p.adopt_own(kConfig), 11);
  EXPECT_EQ(p.claim_version(), 12);  // a diagnostic set of ours: in use unchanged
  EXPECT_EQ(p.version(), 11);
}

TEST(ParamsInUse, ANewerValidSetFromSomeoneElseBecomesTheSetInUse) {
  ParamsInUse p(kConfig, "reident@a", kOwn);
  EXPECT_EQ(p.offer(kOther, 5, kIdentify, true, "identify@b"), ParamsOffer::adopted);
  EXPECT_EQ(p.version(), 5);
  EXPECT_EQ(p.source(), "identify@b");
  EXPECT_DOUBLE_EQ(p.params().c1, kOther.c1);
  EXPECT_EQ(p.offer(kConfig, 5, kIdentify, true, "identify@b"), ParamsOffer::stale);  // same version: not newer
  EXPECT_EQ(p.offer(kConfig, 3, kIdentify, true, "identify@b"), ParamsOffer::stale);
  EXPECT_DOUBLE_EQ(p.params().c1, kOther.c1);
  EXPECT_EQ(p.adopt_own(kConfig), 6);
}

TEST(ParamsInUse, OurOwnEchoIsIgnoredButASecondReidentifierOnTheHostIsNot) {
  ParamsInUse p(kConfig, "reident@a", kOwn);
  const std::int32_t v = p.adopt_own(kOther);
  EXPECT_EQ(p.offer(kOther, v, kOwn, true, "reident@a"), ParamsOffer::echo);
  EXPECT_EQ(p.offer(kOther, v, kOwn, true, "reident@a"), ParamsOffer::echo);  // a UDP repeat
  // Same source, another publisher id: another re-identifier on this host (or our previous run).
  EXPECT_EQ(p.offer(kConfig, 1, kOwn + 1, true, "reident@a"), ParamsOffer::adopted);
  EXPECT_EQ(p.version(), 1);
  // Having adopted it, our own echo is still ours.
  const std::int32_t w = p.adopt_own(kOther);
  EXPECT_EQ(p.offer(kOther, w, kOwn, true, "reident@a"), ParamsOffer::echo);
  EXPECT_EQ(p.params().c1, kOther.c1);
}

TEST(ParamsInUse, SetsOutsideTheModelDomainAreNeverInUse) {
  ParamsInUse p(kConfig, "reident@a", kOwn);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(p.offer(MemParams{0.0, 1e-12, 1.0}, 4, kCtl, true, "x"), ParamsOffer::invalid);
  EXPECT_EQ(p.offer(MemParams{1e-9, -1e-12, 1.0}, 4, kCtl, true, "x"), ParamsOffer::invalid);
  EXPECT_EQ(p.offer(MemParams{1e-9, 1e-12, nan}, 4, kCtl, true, "x"), ParamsOffer::invalid);
  EXPECT_EQ(p.version(), 1);
  EXPECT_EQ(p.highest_seen(), 4);
}

// Commands for ticks first .. last with one version, as one or more HX_COMMAND blocks carry them.
void command_ticks(ParamsInUse& p, std::int64_t first, std::int64_t last, std::int32_t version) {
  for (std::int64_t s = first; s <= last; ++s) p.on_command(s, version);
}

TEST(ParamsInUse, TheAppliedVersionIsUnknownUntilACommandForTheTickOrBefore) {
  ParamsInUse p(kConfig, "reident@a", kOwn);
  EXPECT_EQ(p.applied_version(), ParamsInUse::kUnknownVersion);
  EXPECT_EQ(p.on_sample(0), ParamsInUse::kUnknownVersion);  // no compensator yet
  command_ticks(p, 10, 19, 1);
  EXPECT_EQ(p.on_sample(5), ParamsInUse::kUnknownVersion);
  EXPECT_EQ(p.on_sample(10), 1);
  EXPECT_EQ(p.applied_version(), 1);
  EXPECT_EQ(p.on_sample(40), 1);  // late: the bridge held the last command
}

TEST(ParamsInUse, TheAppliedVersionAtASampleComesFromTheCommandsAtOrBeforeItsTick) {
  ParamsInUse p(kConfig, "reident@a", kOwn);
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
  ParamsInUse p(kConfig, "reident@a", kOwn);
  command_ticks(p, 0, 99, 9);
  EXPECT_EQ(p.highest_seen(), 9);
  EXPECT_EQ(p.version(), 1);
  EXPECT_EQ(p.adopt_own(kOther), 10);
  // Our own set, applied later, is not above anything.
  command_ticks(p, 100, 199, 10);
  EXPECT_EQ(p.claim_version(), 11);
  EXPECT_EQ(p.offer(kOther, 10, kOwn, true, "reident@a"), ParamsOffer::echo);
}

// versions are per publisher. One huge version from anyone is adopted (the compensator
// takes it too) but neither freezes another publisher nor runs our numbering into its ceiling.
TEST(ParamsInUse, AHugeVersionFreezesNoOneAndIsNotFollowed) {
  ParamsInUse p(kConfig, "reident@a", kOwn);
  const std::int32_t huge = std::numeric_limits<std::int32_t>::max();
  EXPECT_EQ(p.offer(kOther, huge, kCtl, true, "forged"), ParamsOffer::adopted);
  EXPECT_EQ(p.offer(kConfig, 2, kIdentify, true, "identify@b"), ParamsOffer::adopted);
  EXPECT_EQ(p.version(), 2);
  command_ticks(p, 0, 9, huge);  // the compensator applied it for a while
  EXPECT_EQ(p.adopt_own(kOther), 3);
  EXPECT_EQ(p.adopt_own(kConfig), 4);  // still counting up, far below the ceiling
  EXPECT_EQ(p.offer(kOther, ParamsInUse::kFollowLimit - 1, kCtl, false, "ctl"), ParamsOffer::invalid);
  EXPECT_EQ(p.claim_version(), ParamsInUse::kFollowLimit);  // below the limit: followed
}

TEST(ParamsInUse, ARestartedPublisherIsAdoptedWhateverItsVersion) {
  ParamsInUse p(kConfig, "reident@a", kOwn);
  EXPECT_EQ(p.offer(kOther, 40, kIdentify, true, "reident@b"), ParamsOffer::adopted);
  const std::uint64_t g = p.generation();
  EXPECT_EQ(p.offer(kConfig, 2, kIdentify + 1, true, "reident@b"), ParamsOffer::adopted);  // restarted
  EXPECT_EQ(p.version(), 2);
  EXPECT_NE(p.generation(), g);  // a refit judged against version 40's set is superseded
  EXPECT_EQ(p.offer(kOther, 39, kIdentify, true, "reident@b"), ParamsOffer::stale);  // the old run's older one
}

// A forged set with our publisher id (the compensator then refuses our own sets as stale): not
// ours, so never the set in use, whatever its version; counted.
TEST(ParamsInUse, ASetWithOurIdThatWeNeverPublishedIsNotAdopted) {
  ParamsInUse p(kConfig, "reident@a", kOwn);
  const std::int32_t huge = std::numeric_limits<std::int32_t>::max();
  EXPECT_EQ(p.offer(kOther, huge, kOwn, true, "reident@a"), ParamsOffer::forged);
  EXPECT_EQ(p.version(), 1);
  EXPECT_EQ(p.source(), "config");
  EXPECT_DOUBLE_EQ(p.params().c1, kConfig.c1);
  EXPECT_EQ(p.forged_sets(), 1u);
  EXPECT_EQ(p.last_forged_version(), huge);
  // Ours still come back as echoes; a version below our highest that we never sent is not one.
  const std::int32_t v = p.adopt_own(kOther);
  EXPECT_EQ(v, 2);  // a huge version is not followed
  const std::int32_t w = p.adopt_own(kConfig);
  EXPECT_EQ(p.offer(kConfig, w, kOwn, true, "reident@a"), ParamsOffer::echo);
  EXPECT_EQ(p.offer(kOther, v, kOwn, true, "reident@a"), ParamsOffer::echo);
  EXPECT_EQ(p.offer(kOther, 1, kOwn, true, "reident@a"), ParamsOffer::forged);  // 1 is the config's: never sent
  EXPECT_EQ(p.offer(kOther, w + 1, kOwn, true, "reident@a"), ParamsOffer::forged);
  EXPECT_EQ(p.version(), w);
  EXPECT_DOUBLE_EQ(p.params().c1, kConfig.c1);
  EXPECT_EQ(p.forged_sets(), 3u);
  EXPECT_EQ(p.last_forged_version(), w + 1);
  // Its version is seen: our next set numbers above it, so the compensator takes ours again.
  EXPECT_EQ(p.adopt_own(kOther), w + 2);
}

TEST(ParamsInUse, TheCompensatorApplyingAForgedSetIsSeen) {
  ParamsInUse p(kConfig, "reident@a", kOwn);
  const std::int32_t huge = std::numeric_limits<std::int32_t>::max();
  EXPECT_FALSE(p.forged_applied());
  EXPECT_EQ(p.offer(kOther, huge, kOwn, true, "forged"), ParamsOffer::forged);
  command_ticks(p, 0, 99, 1);
  p.on_sample(50);
  EXPECT_FALSE(p.forged_applied());  // not yet swapped in
  command_ticks(p, 100, 199, huge);
  p.on_sample(150);
  EXPECT_TRUE(p.forged_applied());
  command_ticks(p, 200, 299, 7);  // someone else's set replaced it
  p.on_sample(250);
  EXPECT_FALSE(p.forged_applied());
}

// Echoes come back within milliseconds; the last kSentKept versions we published are kept.
TEST(ParamsInUse, OnlyTheLastVersionsWePublishedAreKnownAsOurs) {
  ParamsInUse p(kConfig, "reident@a", kOwn);
  const std::int32_t first = p.claim_version();
  std::int32_t last = first;
  for (std::size_t i = 1; i < ParamsInUse::kSentKept; ++i) last = p.claim_version();
  EXPECT_EQ(p.offer(kOther, first, kOwn, false, "reident@a"), ParamsOffer::echo);
  EXPECT_EQ(p.offer(kOther, last, kOwn, false, "reident@a"), ParamsOffer::echo);
  p.claim_version();
  EXPECT_EQ(p.offer(kOther, first, kOwn, false, "reident@a"), ParamsOffer::forged);
  EXPECT_EQ(p.offer(kOther, last, kOwn, false, "reident@a"), ParamsOffer::echo);
}

}  // namespace
}  // namespace hystloop
