// ParamsAdmission: versions are ordered per publisher. A huge version from one publisher freezes
// no other; a restarted publisher (a new id) is accepted whatever its version; the same
// publisher's older or equal version is stale; a full table evicts the least recently used.
#include "loop/params_admission.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <set>

namespace hystloop {
namespace {

constexpr std::int64_t kA = 0x1111;
constexpr std::int64_t kB = -0x2222;
constexpr std::int32_t kMax = std::numeric_limits<std::int32_t>::max();

TEST(ParamsAdmission, AHugeVersionFromOnePublisherDoesNotFreezeAnother) {
  ParamsAdmission a;
  ASSERT_TRUE(a.is_new(kA, kMax));
  a.accept(kA, kMax);
  EXPECT_FALSE(a.is_new(kA, kMax));
  for (std::int32_t v = 2; v < 6; ++v) {
    ASSERT_TRUE(a.is_new(kB, v)) << v;
    a.accept(kB, v);
  }
  EXPECT_EQ(a.last_version(kB), 5);
  EXPECT_EQ(a.last_version(kA), kMax);
}

TEST(ParamsAdmission, TheSamePublishersOlderOrEqualVersionIsStale) {
  ParamsAdmission a;
  a.accept(kA, 7);
  EXPECT_FALSE(a.is_new(kA, 7));  // a UDP repeat
  EXPECT_FALSE(a.is_new(kA, 3));
  EXPECT_TRUE(a.is_new(kA, 8));
  a.accept(kA, 3);  // never lowers
  EXPECT_EQ(a.last_version(kA), 7);
}

TEST(ParamsAdmission, ARestartedPublisherWithALowerVersionIsAccepted) {
  ParamsAdmission a;
  a.accept(kA, 40);  // the re-identifier before its restart
  const std::int64_t restarted = new_publisher_id();
  ASSERT_NE(restarted, kA);
  EXPECT_TRUE(a.is_new(restarted, 2));
}

TEST(ParamsAdmission, LegacySetsWithoutAnIdAreOnePublisher) {
  ParamsAdmission a;
  a.accept(0, 9);
  EXPECT_FALSE(a.is_new(0, 9));
  EXPECT_TRUE(a.is_new(0, 10));
  EXPECT_TRUE(a.is_new(kA, 1));
}

TEST(ParamsAdmission, AFullTableEvictsTheLeastRecentlyUsed) {
  ParamsAdmission a;
  for (std::size_t i = 0; i < ParamsAdmission::kPublishers; ++i) a.accept(100 + static_cast<std::int64_t>(i), 50);
  EXPECT_EQ(a.publishers(), ParamsAdmission::kPublishers);
  a.accept(100, 51);  // publisher 100 used again: 101 is now the oldest
  a.accept(999, 1);   // a new one takes 101's row
  EXPECT_EQ(a.evictions(), 1u);
  EXPECT_EQ(a.publishers(), ParamsAdmission::kPublishers);
  EXPECT_TRUE(a.is_new(101, 1));  // forgotten: new again
  EXPECT_FALSE(a.is_new(100, 51));
  EXPECT_FALSE(a.is_new(102, 50));
  EXPECT_FALSE(a.is_new(999, 1));
}

TEST(ParamsAdmission, EachRefusalIsLoggedOncePerReasonPerPublisher) {
  ParamsAdmission a;
  EXPECT_TRUE(a.first_refusal(kA, ParamsRefusal::stale));
  EXPECT_FALSE(a.first_refusal(kA, ParamsRefusal::stale));
  EXPECT_TRUE(a.first_refusal(kA, ParamsRefusal::invalid));
  EXPECT_TRUE(a.first_refusal(kB, ParamsRefusal::stale));
  EXPECT_FALSE(a.first_refusal(kB, ParamsRefusal::stale));
  EXPECT_TRUE(a.first_refusal(kB, ParamsRefusal::refused));
  a.accept(kA, 3);  // accepting keeps what was logged
  EXPECT_FALSE(a.first_refusal(kA, ParamsRefusal::invalid));
  EXPECT_TRUE(a.is_new(kB, 1));  // a refusal records no version
}

constexpr std::int64_t kSecond_ns = 1'000'000'000;

// One forged set with the re-identifier's own id and the largest version: every later set of the
// re-identifier is stale. Two refused below the accepted version within the window freeze it out.
TEST(ParamsAdmission, APublisherWhoseSetsKeepBeingRefusedBelowItsAcceptedVersionIsFrozenOut) {
  ParamsAdmission a;
  ParamsAdmission::FrozenList out;
  a.accept(kA, 2);
  a.accept(kA, kMax);  // forged
  std::int64_t t = 100 * kSecond_ns;
  ASSERT_FALSE(a.is_new(kA, 3));
  EXPECT_TRUE(a.refuse_stale(kA, 3, t));
  EXPECT_EQ(a.frozen(t, out), 0u);  // one may be a datagram overtaken by its successor
  EXPECT_TRUE(a.refuse_stale(kA, 4, t += 5 * kSecond_ns));
  ASSERT_EQ(a.frozen(t, out), 1u);
  EXPECT_EQ(out[0].publisher, kA);
  EXPECT_EQ(out[0].refused_version, 4);
  EXPECT_EQ(out[0].accepted_version, kMax);
  EXPECT_EQ(out[0].refusals, 2u);
  EXPECT_TRUE(a.refuse_stale(kA, 5, t += kSecond_ns));
  ASSERT_EQ(a.frozen(t, out), 1u);
  EXPECT_EQ(out[0].refusals, 3u);
  // Still frozen until the window has passed since the last refusal: then it went quiet.
  EXPECT_EQ(a.frozen(t + ParamsAdmission::kFrozenWindowNs, out), 1u);
  EXPECT_EQ(a.frozen(t + ParamsAdmission::kFrozenWindowNs + 1, out), 0u);
  // After a quiet spell one refusal starts a new run: not frozen again at once.
  t += 2 * ParamsAdmission::kFrozenWindowNs;
  EXPECT_TRUE(a.refuse_stale(kA, 6, t));
  EXPECT_EQ(a.frozen(t, out), 0u);
  EXPECT_TRUE(a.refuse_stale(kA, 7, t += kSecond_ns));
  EXPECT_EQ(a.frozen(t, out), 1u);
}

TEST(ParamsAdmission, RefusalsFurtherApartThanTheWindowDoNotFreeze) {
  ParamsAdmission a;
  ParamsAdmission::FrozenList out;
  a.accept(kA, 50);
  std::int64_t t = 0;
  for (std::int32_t v = 10; v < 20; ++v) {
    EXPECT_TRUE(a.refuse_stale(kA, v, t += ParamsAdmission::kFrozenWindowNs + 1));
    EXPECT_EQ(a.frozen(t, out), 0u) << v;
  }
}

TEST(ParamsAdmission, AnAcceptedSetClearsTheFreeze) {
  ParamsAdmission a;
  ParamsAdmission::FrozenList out;
  a.accept(kA, 40);
  a.refuse_stale(kA, 3, 0);
  a.refuse_stale(kA, 4, kSecond_ns);
  ASSERT_EQ(a.frozen(kSecond_ns, out), 1u);
  a.accept(kA, 41);  // its sets are taken again
  EXPECT_EQ(a.frozen(kSecond_ns, out), 0u);
  a.refuse_stale(kA, 5, 2 * kSecond_ns);  // a new run starts from none
  EXPECT_EQ(a.frozen(2 * kSecond_ns, out), 0u);
}

// hystloop-ctl params and hystloop-identify --publish send every set several times: the repeats
// of the accepted version are stale, but no sign of a freeze.
TEST(ParamsAdmission, RepeatsOfTheAcceptedVersionDoNotFreeze) {
  ParamsAdmission a;
  ParamsAdmission::FrozenList out;
  a.accept(kA, 7);
  for (std::int64_t i = 0; i < 10; ++i) EXPECT_FALSE(a.refuse_stale(kA, 7, i * 5'000'000));  // every 5 ms
  EXPECT_EQ(a.frozen(kSecond_ns, out), 0u);
}

TEST(ParamsAdmission, OnlyThePublisherFrozenOutIsNamed) {
  ParamsAdmission a;
  ParamsAdmission::FrozenList out;
  a.accept(kA, kMax);
  a.accept(kB, 9);
  for (std::int64_t i = 0; i < 3; ++i) {
    a.refuse_stale(kA, 2 + static_cast<std::int32_t>(i), i * kSecond_ns);
    a.refuse_stale(kB, 9, i * kSecond_ns);  // repeats
  }
  ASSERT_EQ(a.frozen(3 * kSecond_ns, out), 1u);
  EXPECT_EQ(out[0].publisher, kA);
}

TEST(ParamsAdmission, PublisherIdsAreNonZeroAndDiffer) {
  std::set<std::int64_t> ids;
  for (int i = 0; i < 100; ++i) {
    const std::int64_t id = new_publisher_id();
    EXPECT_NE(id, 0);
    ids.insert(id);
  }
  EXPECT_EQ(ids.size(), 100u);
}

}  // namespace
}  // namespace hystloop
