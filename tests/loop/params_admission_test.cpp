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
