#include "ident/stage_identification.hpp"

#include <charconv>
#include <complex>
#include <numbers>

#include "core/errors.hpp"

namespace hystloop {

std::string StageIdentification::reason() const {
  if (!frf.ok()) return "no frequency response: " + frf.reason;
  if (!fit.ok()) return "no stage model: " + fit.reason;
  return {};
}

void set_stage_order(std::string_view order, StageFitOptions& options) {
  if (order == "auto") {
    options.auto_order = true;
    return;
  }
  int m = -1, n = -1;
  const std::size_t slash = order.find('/');
  if (slash != std::string_view::npos) {
    const char* end = order.data() + order.size();
    const auto [pm, em] = std::from_chars(order.data(), order.data() + slash, m);
    const auto [pn, en] = std::from_chars(order.data() + slash + 1, end, n);
    if (em != std::errc{} || pm != order.data() + slash || en != std::errc{} || pn != end) m = n = -1;
  }
  if (m < 0 || n < 1 || m > n) {
    throw ParameterError(
        "order", "NUM/DEN with 0 <= NUM <= DEN, DEN >= 1 (e.g. 2/4), or auto (got '" + std::string(order) + "')");
  }
  options.auto_order = false;
  options.numerator_order = m;
  options.denominator_order = n;
}

double sigma_degrees_of_freedom(const FrequencyResponse& frf) noexcept {
  const double nu = frf.total_available ? 2.0 * static_cast<double>(frf.realisations - 1)
                                        : 2.0 * static_cast<double>(frf.realisations * (frf.periods_used - 1));
  return nu > 2.0 ? nu : 0.0;  // E[1 / sigma^2] = nu / (nu - 2) / sigma0^2 exists only above 2
}

StageIdentification identify_stage_dynamics(std::span<const double> u, std::span<const double> y,
                                            std::span<const std::size_t> lines, const FrfOptions& frf_options,
                                            StageFitOptions fit_options, bool sampled_at_tick_end) {
  StageIdentification r;
  r.frf = estimate_frequency_response(u, y, lines, frf_options);
  if (!r.frf.ok()) return r;
  if (fit_options.zoh_sample_rate_Hz > 0.0 && sampled_at_tick_end) {
    for (std::size_t i = 0; i < r.frf.G.size(); ++i) {
      r.frf.G[i] *= std::polar(1.0, -2.0 * std::numbers::pi * r.frf.frequency_Hz[i] / frf_options.sample_rate_Hz);
    }
  }
  fit_options.sigma_dof = sigma_degrees_of_freedom(r.frf);
  r.fit = fit_stage_model({r.frf.frequency_Hz, r.frf.G, r.sigma()}, fit_options);
  return r;
}

double model_known_to_hz(const StageIdentification& id, double from_hz, double within) {
  if (!id.ok()) return 0.0;
  const FrequencyResponse& frf = id.frf;
  const std::vector<double>& sigma = id.sigma();
  double known = 0.0;
  for (std::size_t i = 0; i < frf.frequency_Hz.size(); ++i) {
    const double f = frf.frequency_Hz[i];
    if (f < from_hz) continue;
    const std::complex<double> m = id.fit.sampled_response(f);
    const double bound = (std::abs(frf.G[i] - m) + 2.0 * sigma[i]) / std::abs(m);
    if (!(bound <= within)) break;
    known = f;
  }
  return known;
}

}  // namespace hystloop
