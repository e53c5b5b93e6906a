#include "ident/frequency_response.hpp"

#include <cmath>
#include <limits>
#include <numbers>

#include "core/errors.hpp"

namespace hystloop {

void FrfOptions::validate() const {
  require_positive("sample_rate_Hz", sample_rate_Hz);
  if (period_samples < 4) throw ParameterError("period_samples", "must be at least 4");
  if (realisations < 1) throw ParameterError("realisations", "must be at least 1");
  if (periods < transient_periods + 2) {
    throw ParameterError("periods", "must exceed transient_periods by at least 2 (the noise variance needs two)");
  }
}

namespace {

using C = std::complex<double>;

// DFT (2/N scaling) of one period at the given lines, from a table of N unit phasors.
void dft_lines(const double* x, std::size_t n_per, std::span<const std::size_t> lines, const std::vector<C>& table,
               C* out) {
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::size_t k = lines[i];
    double re = 0.0, im = 0.0;
    std::size_t idx = 0;
    for (std::size_t n = 0; n < n_per; ++n) {
      re += x[n] * table[idx].real();
      im += x[n] * table[idx].imag();
      idx += k;
      if (idx >= n_per) idx -= n_per;
    }
    out[i] = C(re, im) * (2.0 / static_cast<double>(n_per));
  }
}

FrequencyResponse refuse(FrequencyResponse r, FitStatus s, std::string why) {
  r.status = s;
  r.reason = std::move(why);
  return r;
}

}  // namespace

FrequencyResponse estimate_frequency_response(std::span<const double> u, std::span<const double> y,
                                              std::span<const std::size_t> lines, const FrfOptions& o) {
  o.validate();
  FrequencyResponse res;
  const std::size_t n_per = o.period_samples, P = o.periods, R = o.realisations, F = lines.size();
  const std::size_t expected = n_per * P * R;
  if (u.size() != expected || y.size() != expected) {
    return refuse(res, FitStatus::size_mismatch,
                  "u has " + std::to_string(u.size()) + " and y " + std::to_string(y.size()) +
                      " samples; periods * realisations * period_samples = " + std::to_string(expected));
  }
  if (F == 0) return refuse(res, FitStatus::size_mismatch, "lines is empty");
  for (std::size_t i = 0; i < F; ++i) {
    if (lines[i] == 0 || 2 * lines[i] >= n_per) {
      return refuse(res, FitStatus::out_of_range,
                    "lines[" + std::to_string(i) + "] = " + std::to_string(lines[i]) + " is not in (0, N/2)");
    }
  }
  for (std::size_t i = 0; i < expected; ++i) {
    if (!std::isfinite(u[i]) || !std::isfinite(y[i])) {
      return refuse(res, FitStatus::non_finite_data,
                    "sample " + std::to_string(i) + ": " + (std::isfinite(u[i]) ? "y" : "u") + " is not finite");
    }
  }
  std::vector<C> table(n_per);
  for (std::size_t n = 0; n < n_per; ++n)
    table[n] = std::polar(1.0, -2.0 * std::numbers::pi * static_cast<double>(n) / static_cast<double>(n_per));

  // A line whose input is below 1e-9 of the record's rms (rounding of an unexcited line) is no line.
  double mean_u = 0.0, ss_u = 0.0;
  for (double v : u) mean_u += v;
  mean_u /= static_cast<double>(expected);
  for (double v : u) ss_u += (v - mean_u) * (v - mean_u);
  const double u_floor = 1e-9 * std::sqrt(ss_u / static_cast<double>(expected));
  const std::size_t Pu = P - o.transient_periods;
  const double pu = static_cast<double>(Pu), rr = static_cast<double>(R);
  std::vector<C> Up(Pu * F), Yp(Pu * F);  // one realisation's periods
  std::vector<C> Gr(R * F);
  std::vector<double> var_gr(R * F);
  std::vector<C> syu(F, 0.0);
  std::vector<double> suu(F, 0.0), syy(F, 0.0), uabs(F, 0.0), snr(F, 0.0);
  for (std::size_t r = 0; r < R; ++r) {
    for (std::size_t p = 0; p < Pu; ++p) {
      const std::size_t off = (r * P + o.transient_periods + p) * n_per;
      dft_lines(u.data() + off, n_per, lines, table, &Up[p * F]);
      dft_lines(y.data() + off, n_per, lines, table, &Yp[p * F]);
    }
    for (std::size_t i = 0; i < F; ++i) {
      C um = 0.0, ym = 0.0;
      for (std::size_t p = 0; p < Pu; ++p) {
        const C a = Up[p * F + i], b = Yp[p * F + i];
        um += a, ym += b;
        syu[i] += b * std::conj(a), suu[i] += std::norm(a), syy[i] += std::norm(b);
      }
      um /= pu, ym /= pu;
      double vu = 0.0, vy = 0.0;
      C cyu = 0.0;
      for (std::size_t p = 0; p < Pu; ++p) {
        const C du = Up[p * F + i] - um, dy = Yp[p * F + i] - ym;
        vu += std::norm(du), vy += std::norm(dy), cyu += dy * std::conj(du);
      }
      const double scale = 1.0 / (pu * (pu - 1.0));  // variance of the period mean
      vu *= scale, vy *= scale, cyu *= scale;
      if (!(std::abs(um) > u_floor)) {
        return refuse(res, FitStatus::constant_input,
                      "realisation " + std::to_string(r) + ", line " + std::to_string(lines[i]) +
                          ": the input has no component there (is it an excited line?)");
      }
      const C g = ym / um;
      Gr[r * F + i] = g;
      // var G = var(Y - G U) / |U|^2 to first order: the expansion in the header.
      var_gr[r * F + i] = std::max(0.0, (vy + std::norm(g) * vu - 2.0 * std::real(std::conj(g) * cyu)) / std::norm(um));
      uabs[i] += std::abs(um) / rr;
      snr[i] += (vy > 0.0 ? std::abs(ym) / std::sqrt(vy) : std::numeric_limits<double>::infinity()) / rr;
    }
  }
  res.lines.assign(lines.begin(), lines.end());
  res.periods_used = Pu;
  res.realisations = R;
  res.total_available = R >= 2;
  double ratio_sum = 0.0;
  std::size_t ratio_n = 0;
  for (std::size_t i = 0; i < F; ++i) {
    C gm = 0.0;
    double vn = 0.0;
    for (std::size_t r = 0; r < R; ++r) gm += Gr[r * F + i], vn += var_gr[r * F + i];
    gm /= rr;
    vn /= rr * rr;
    double vt = vn;
    if (R >= 2) {
      vt = 0.0;
      for (std::size_t r = 0; r < R; ++r) vt += std::norm(Gr[r * F + i] - gm);
      vt /= rr * (rr - 1.0);
      if (vn > 0.0) ratio_sum += vt / vn, ++ratio_n;
    }
    res.frequency_Hz.push_back(static_cast<double>(lines[i]) * o.sample_rate_Hz / static_cast<double>(n_per));
    res.G.push_back(gm);
    res.sigma_noise.push_back(std::sqrt(vn));
    res.sigma_total.push_back(std::sqrt(vt));
    res.coherence.push_back(suu[i] > 0.0 && syy[i] > 0.0 ? std::norm(syu[i]) / (suu[i] * syy[i]) : 0.0);
    res.input_amplitude_V.push_back(uabs[i]);
    res.output_snr.push_back(snr[i]);
  }
  res.distortion_ratio = ratio_n ? ratio_sum / static_cast<double>(ratio_n) : 1.0;
  res.status = FitStatus::ok;
  return res;
}

}  // namespace hystloop
