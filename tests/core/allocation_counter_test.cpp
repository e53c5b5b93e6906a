#include "support/allocation_counter.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

namespace hystloop::testing {
namespace {

// The counter must see allocations, or every "allocates nothing" test would pass vacuously.
TEST(AllocationCounter, SeesAllocationsAndOnlyThose) {
  AllocationCounter none;
  volatile double x = 1.0;
  for (int i = 0; i < 100; ++i) x = x * 1.000001;
  EXPECT_EQ(none.allocations(), 0u);

  AllocationCounter some;
  auto p = std::make_unique<int>(3);
  std::vector<double> v(10);
  EXPECT_EQ(some.allocations(), 2u);
  EXPECT_EQ(*p + static_cast<int>(v.size()), 13);
}

}  // namespace
}  // namespace hystloop::testing
