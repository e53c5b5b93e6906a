#include "ident/branches.hpp"

#include <algorithm>
#include <cmath>

#include "models/reversal_detector.hpp"

namespace hystloop {

std::vector<std::size_t> find_reversals(std::span<const double> u, double dead_band_V) {
  std::vector<std::size_t> reversals;
  if (u.empty()) return reversals;
  ReversalDetector detector(std::max(dead_band_V, 0.0));
  detector.reset(u[0]);
  std::size_t extremum = 0;  // the sample at detector.extremum()
  for (std::size_t k = 1; k < u.size(); ++k) {
    const ReversalDetector::Event event = detector.update(u[k]);
    if (event == ReversalDetector::Event::kReversal) reversals.push_back(extremum);
    if (event != ReversalDetector::Event::kNone) extremum = k;
  }
  return reversals;
}

std::vector<BranchSegment> split_branches(std::span<const double> u, double dead_band_V) {
  const std::vector<std::size_t> rev = find_reversals(u, dead_band_V);
  std::vector<BranchSegment> branches;
  branches.reserve(rev.size());
  for (std::size_t i = 0; i < rev.size(); ++i) {
    BranchSegment b;
    b.begin = rev[i];
    b.end = i + 1 < rev.size() ? rev[i + 1] : u.size();
    b.origin_u = u[b.begin];
    // Direction after the reversal: towards the next sample that differs.
    double dir = 0.0;
    for (std::size_t k = b.begin + 1; k < u.size() && dir == 0.0; ++k) {
      if (u[k] != b.origin_u) dir = u[k] > b.origin_u ? 1.0 : -1.0;
    }
    b.direction = dir == 0.0 ? 1.0 : dir;
    if (b.size() > 0) branches.push_back(b);
  }
  return branches;
}

double estimate_noise_rms(std::span<const double> y) {
  if (y.size() < 8) return 0.0;
  std::vector<double> d(y.size() - 3);
  for (std::size_t k = 0; k + 3 < y.size(); ++k) {
    d[k] = std::abs(y[k + 3] - 3.0 * y[k + 2] + 3.0 * y[k + 1] - y[k]);
  }
  auto mid = d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2);
  std::nth_element(d.begin(), mid, d.end());
  return 1.482602218505602 * *mid / std::sqrt(20.0);
}

}  // namespace hystloop
