#pragma once
// Sums of counters that stop at the largest value instead of wrapping. Counts fed by what came
// off the wire (a forged tick number can make one gap 2^53 ticks long, and a channel's gaps add
// up) must never wrap to a small number that looks plausible: UINT64_MAX says "at least this".

#include <cstdint>
#include <limits>

namespace hystloop {

constexpr std::uint64_t saturating_add(std::uint64_t a, std::uint64_t b) noexcept {
  return b > std::numeric_limits<std::uint64_t>::max() - a ? std::numeric_limits<std::uint64_t>::max() : a + b;
}

// counter += n, saturating.
constexpr void add_saturating(std::uint64_t& counter, std::uint64_t n) noexcept {
  counter = saturating_add(counter, n);
}

}  // namespace hystloop
