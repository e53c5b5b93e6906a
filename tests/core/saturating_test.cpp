// saturating_add: a sum of counters stops at UINT64_MAX instead of wrapping.
#include "core/saturating.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

namespace hystloop {
namespace {

constexpr std::uint64_t kTop = std::numeric_limits<std::uint64_t>::max();

TEST(SaturatingAdd, AddsBelowTheTop) {
  EXPECT_EQ(saturating_add(0, 0), 0u);
  EXPECT_EQ(saturating_add(2, 3), 5u);
  EXPECT_EQ(saturating_add(kTop - 1, 1), kTop);
  EXPECT_EQ(saturating_add(kTop, 0), kTop);
  static_assert(saturating_add(40, 2) == 42);
}

TEST(SaturatingAdd, StopsAtTheTopInsteadOfWrapping) {
  EXPECT_EQ(saturating_add(kTop, 1), kTop);
  EXPECT_EQ(saturating_add(1, kTop), kTop);
  EXPECT_EQ(saturating_add(kTop - 1, kTop - 1), kTop);  // wraps to 2^64 - 3 without saturation
  std::uint64_t counter = kTop - 2;
  add_saturating(counter, 1);
  EXPECT_EQ(counter, kTop - 1);
  add_saturating(counter, 5);
  EXPECT_EQ(counter, kTop);
  add_saturating(counter, kTop);
  EXPECT_EQ(counter, kTop);
}

}  // namespace
}  // namespace hystloop
