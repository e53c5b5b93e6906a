#include "models/multisine.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include <unsupported/Eigen/FFT>

#include "core/errors.hpp"

namespace hystloop {

namespace {

// The sum of n's prime factors, with multiplicity (2000 = 2^4 5^3: 23): an FFT's cost per sample.
std::size_t prime_factor_sum(std::size_t n) {
  std::size_t sum = 0;
  for (std::size_t p = 2; p * p <= n; ++p) {
    while (n % p == 0) sum += p, n /= p;
  }
  return n > 1 ? sum + n : sum;
}

std::vector<std::size_t> lines_unchecked(const MultisineOptions& o) {
  const double df = o.sample_rate_Hz / static_cast<double>(o.period_samples);
  const std::size_t nyquist = (o.period_samples - 1) / 2;  // lines strictly below fs / 2
  const double k_lo = std::max(1.0, std::ceil(o.f_min_Hz / df - 1e-9));
  const double k_hi = std::min(static_cast<double>(nyquist), std::floor(o.f_max_Hz / df + 1e-9));
  std::vector<std::size_t> k;
  if (k_hi < k_lo) return k;
  const auto lo = static_cast<std::size_t>(k_lo), hi = static_cast<std::size_t>(k_hi);
  switch (o.lines) {
    case MultisineLines::all:
      for (std::size_t i = lo; i <= hi; ++i) k.push_back(i);
      break;
    case MultisineLines::odd:
      for (std::size_t i = lo; i <= hi; ++i)
        if (i % 2 == 1) k.push_back(i);
      break;
    case MultisineLines::log: {
      const double decades = std::log10(k_hi / k_lo);
      const auto count = static_cast<std::size_t>(std::ceil(decades * o.lines_per_decade)) + 1;
      for (std::size_t i = 0; i < count; ++i) {
        const double t = count > 1 ? static_cast<double>(i) / static_cast<double>(count - 1) : 0.0;
        const auto line = static_cast<std::size_t>(std::lround(k_lo * std::pow(k_hi / k_lo, t)));
        if (k.empty() || line > k.back()) k.push_back(line);
      }
      break;
    }
  }
  return k;
}

}  // namespace

void MultisineOptions::validate() const {
  require_positive("sample_rate_Hz", sample_rate_Hz);
  if (period_samples < 4) throw ParameterError("period_samples", "must be at least 4");
  require_positive("f_min_Hz", f_min_Hz);
  require_positive("f_max_Hz", f_max_Hz);
  if (!(f_max_Hz >= f_min_Hz)) throw ParameterError("f_max_Hz", "must be >= f_min_Hz");
  if (!(f_min_Hz < 0.5 * sample_rate_Hz)) throw ParameterError("f_min_Hz", "must be below the Nyquist frequency");
  if (lines == MultisineLines::log) require_positive("lines_per_decade", lines_per_decade);
  require_positive("amplitude_V", amplitude_V);
  require_finite("offset_V", offset_V);
  if (periods < 1) throw ParameterError("periods", "must be at least 1");
  if (realisations < 1) throw ParameterError("realisations", "must be at least 1");
  if (lines_unchecked(*this).empty()) {
    throw ParameterError("f_min_Hz", "no DFT line of the period (resolution " +
                                         number_text(sample_rate_Hz / static_cast<double>(period_samples)) +
                                         " Hz) lies in [f_min_Hz, f_max_Hz] below Nyquist");
  }
}

std::vector<std::size_t> multisine_lines(const MultisineOptions& options) {
  options.validate();
  return lines_unchecked(options);
}

Multisine design_multisine(const MultisineOptions& o) {
  Multisine m;
  m.lines = multisine_lines(o);
  m.sample_rate_Hz = o.sample_rate_Hz;
  m.period_samples = o.period_samples;
  m.periods = o.periods;
  m.realisations = o.realisations;
  const std::size_t n_per = o.period_samples, f = m.lines.size();
  for (std::size_t k : m.lines)
    m.frequency_Hz.push_back(static_cast<double>(k) * o.sample_rate_Hz / static_cast<double>(n_per));
  // A period is sum_k cos(2 pi k n / N + phi_k) = Re sum_k e^{j phi_k} e^{j 2 pi k n / N}: one inverse
  // FFT of the lines' phasors per realisation, about N (sum of N's prime factors) operations, where
  // the sum written out costs F N (600 lines of 2000 ticks: 23 against 600 per sample). A
  // compensator designs it as the request arrives, on the thread that answers the bridge. Eigen's FFT has no fast
  // algorithm for a large prime factor, so where N's prime factors add up to more than the lines, the sum is written
  // out (a table of N angles keeps it exact).
  const bool use_fft = prime_factor_sum(n_per) <= f;
  Eigen::FFT<double> fft;
  fft.SetFlag(Eigen::FFT<double>::Unscaled);
  std::vector<double> c, s;
  if (!use_fft) {
    c.resize(n_per), s.resize(n_per);
    for (std::size_t i = 0; i < n_per; ++i) {
      const double a = 2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(n_per);
      c[i] = std::cos(a), s[i] = std::sin(a);
    }
  }
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
  m.u_V.assign(o.realisations * o.periods * n_per, o.offset_V);
  std::vector<std::complex<double>> spectrum(use_fft ? n_per : 0), time(use_fft ? n_per : 0);
  std::vector<double> period(n_per);
  for (std::size_t r = 0; r < o.realisations; ++r) {
    std::fill(spectrum.begin(), spectrum.end(), std::complex<double>(0.0, 0.0));
    std::fill(period.begin(), period.end(), 0.0);
    for (std::size_t i = 0; i < f; ++i) {
      const double ph = phase(rng);
      m.phase_rad.push_back(ph);
      const std::size_t k = m.lines[i];
      if (use_fft) {
        spectrum[k] = std::polar(1.0, ph);
        continue;
      }
      const double cp = std::cos(ph), sp = std::sin(ph);
      for (std::size_t n = 0; n < n_per; ++n) {
        const std::size_t idx = (k * n) % n_per;
        period[n] += c[idx] * cp - s[idx] * sp;
      }
    }
    if (use_fft) {
      fft.inv(time, spectrum);
      for (std::size_t n = 0; n < n_per; ++n) period[n] = time[n].real();
    }
    double amplitude = o.amplitude_V / std::sqrt(0.5 * static_cast<double>(f));
    if (o.amplitude_mode == MultisineAmplitude::peak) {
      double peak = 0.0;
      for (double v : period) peak = std::max(peak, std::abs(v));
      amplitude = o.amplitude_V / peak;
    }
    m.line_amplitude_V.push_back(amplitude);
    for (std::size_t p = 0; p < o.periods; ++p) {
      double* out = m.u_V.data() + (r * o.periods + p) * n_per;
      for (std::size_t n = 0; n < n_per; ++n) out[n] += amplitude * period[n];
    }
  }
  return m;
}

}  // namespace hystloop
