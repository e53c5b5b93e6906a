#include "core/edit_distance.hpp"

#include <gtest/gtest.h>

namespace hystloop {
namespace {

TEST(EditDistance, CountsInsertionsDeletionsSubstitutionsAndSwaps) {
  EXPECT_EQ(edit_distance("", ""), 0U);
  EXPECT_EQ(edit_distance("gain", "gain"), 0U);
  EXPECT_EQ(edit_distance("", "gain"), 4U);
  EXPECT_EQ(edit_distance("gain", ""), 4U);
  EXPECT_EQ(edit_distance("gian", "gain"), 1U);       // a swap of neighbours is one edit
  EXPECT_EQ(edit_distance("gain", "gains"), 1U);      // insertion
  EXPECT_EQ(edit_distance("u_max_V", "u_mx_V"), 1U);  // deletion
  EXPECT_EQ(edit_distance("kp", "ki"), 1U);           // substitution
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3U);
  EXPECT_EQ(edit_distance("ca", "abc"), 3U);     // optimal string alignment: no edit of a swapped pair
  EXPECT_EQ(edit_distance("Gain", "gain"), 1U);  // case-sensitive
}

TEST(EditDistance, IsSymmetric) {
  for (const char* a : {"", "rate_hz", "ratehz", "hz_rate", "window_s"}) {
    for (const char* b : {"", "rate_hz", "rtae_hz", "windows_s"})
      EXPECT_EQ(edit_distance(a, b), edit_distance(b, a)) << a << " / " << b;
  }
}

}  // namespace
}  // namespace hystloop
