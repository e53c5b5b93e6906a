#pragma once
// Counts heap allocations made by the current thread, so a test can prove that a
// per-sample path allocates nothing:
//
//   hystloop::testing::AllocationCounter counter;
//   for (...) model.forward(u);
//   EXPECT_EQ(counter.allocations(), 0u);
//
// Every test executable links the replacement operator new/delete that feeds it
// (tests/support/allocation_counter.cpp), so this works in any test.

#include <cstddef>

namespace hystloop::testing {

// Allocations (operator new / new[], any alignment) made by this thread since start.
std::size_t thread_allocation_count() noexcept;

class AllocationCounter {
 public:
  AllocationCounter() noexcept : start_(thread_allocation_count()) {}
  std::size_t allocations() const noexcept { return thread_allocation_count() - start_; }

 private:
  std::size_t start_;
};

}  // namespace hystloop::testing
