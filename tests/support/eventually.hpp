#pragma once
// Waiting on another thread in a test: polls `done` every millisecond until it holds or a deadline
// generous for a loaded machine and a sanitizer build passes (10 s); true if it held. A test
// asserts on the result, never on how long it took.

#include <chrono>
#include <thread>

namespace hystloop::testing {

template <class Condition>
bool eventually(Condition done) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!done()) {
    if (std::chrono::steady_clock::now() >= until) return done();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

}  // namespace hystloop::testing
