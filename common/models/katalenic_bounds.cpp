#include "models/katalenic_bounds.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"

namespace hystloop {

void KatalenicFamily::validate() const {
  require_positive("k1", k1);
  require_positive("k2", k2);
  require_non_negative("dk1", dk1);
  require_non_negative("dk2", dk2);
  if (!(dk1 < k1)) throw ParameterError("dk1", "must be < k1 so that every k1 of the family is > 0");
  if (!(dk2 < k2)) throw ParameterError("dk2", "must be < k2 so that every k2 of the family is > 0");
}

double katalenic_error_envelope(double k1, double k1_bar, double k2, double k2_bar, double x) noexcept {
  return k1_bar - k1 + 2.0 * (k1 * std::exp(-k2 * x) - k1_bar * std::exp(-k2_bar * x));
}

double katalenic_error_extremum(double k1, double k1_bar, double k2, double k2_bar) noexcept {
  if (k2_bar == k2) return 0.0;  // (14) is then monotone in x: no interior extremum
  const double x = std::log((k1_bar * k2_bar) / (k1 * k2)) / (k2_bar - k2);
  return std::isfinite(x) ? std::max(x, 0.0) : 0.0;
}

double katalenic_error_peak(double k1, double k1_bar, double k2, double k2_bar) noexcept {
  const double x = katalenic_error_extremum(k1, k1_bar, k2, k2_bar);
  return std::max(std::abs(k1_bar - k1), std::abs(katalenic_error_envelope(k1, k1_bar, k2, k2_bar, x)));
}

double katalenic_inverse_error_bound(double k1, double k2, double k1_bar_lo, double k1_bar_hi, double k2_bar_lo,
                                     double k2_bar_hi) noexcept {
  double bound = 0.0;
  for (double k1_bar : {k1_bar_lo, k1_bar_hi}) {
    for (double k2_bar : {k2_bar_lo, k2_bar_hi}) {
      bound = std::max(bound, katalenic_error_peak(k1, k1_bar, k2, k2_bar));
    }
  }
  return bound;
}

double katalenic_inverse_error_bound(const KatalenicFamily& f) {
  f.validate();
  return katalenic_inverse_error_bound(f.k1, f.k2, f.k1 - f.dk1, f.k1 + f.dk1, f.k2 - f.dk2, f.k2 + f.dk2);
}

double katalenic_compensation_error_bound(const KatalenicFamily& family) {
  return katalenic_inverse_error_bound(family);
}

double katalenic_compensation_error_bound(const KatalenicFamily& family, const ShapingFunction& output_shaping) {
  return katalenic_compensation_error_bound(family) * output_shaping.max_slope();
}

double katalenic_k2_deviation(const KatalenicParams& params) noexcept { return std::abs(params.k2_slope) * params.k1; }

double katalenic_input_dependent_k2_bound(const KatalenicParams& params, double dk1) noexcept {
  const double lo = params.k2_min();
  const double hi = params.k2_max();
  const double dk2 = katalenic_k2_deviation(params);
  constexpr int kSteps = 256;
  double bound = 0.0;
  for (int i = 0; i <= kSteps; ++i) {
    const double k2 = lo + (hi - lo) * static_cast<double>(i) / kSteps;
    bound = std::max(bound, katalenic_inverse_error_bound(params.k1, k2, params.k1 - dk1, params.k1 + dk1,
                                                          std::max(k2 - dk2, lo), std::min(k2 + dk2, hi)));
  }
  return bound;
}

}  // namespace hystloop
