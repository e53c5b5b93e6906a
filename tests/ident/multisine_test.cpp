// The multisine's spectrum (only the excited lines, all at one amplitude), its periodicity, its
// amplitude scaling and its refusals.
#include "models/multisine.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <set>

#include "core/errors.hpp"

namespace hystloop {
namespace {

// Full DFT (2/N scaling) of one period starting at x.
std::vector<std::complex<double>> dft(const double* x, std::size_t n) {
  std::vector<std::complex<double>> X(n / 2 + 1);
  for (std::size_t k = 0; k < X.size(); ++k) {
    std::complex<double> s = 0.0;
    for (std::size_t i = 0; i < n; ++i)
      s += x[i] * std::polar(1.0, -2.0 * std::numbers::pi * static_cast<double>((k * i) % n) / static_cast<double>(n));
    X[k] = s * (2.0 / static_cast<double>(n));
  }
  return X;
}

MultisineOptions small() {
  MultisineOptions o;
  o.period_samples = 400;  // 25 Hz lines
  o.f_min_Hz = 100.0;
  o.f_max_Hz = 3000.0;
  o.amplitude_V = 2.0;
  o.offset_V = 1.5;
  o.periods = 3;
  o.realisations = 2;
  o.seed = 7;
  return o;
}

TEST(Multisine, OnlyTheExcitedLinesCarryPowerAllAtOneAmplitude) {
  for (MultisineLines kind : {MultisineLines::all, MultisineLines::odd, MultisineLines::log}) {
    MultisineOptions o = small();
    o.lines = kind;
    const Multisine m = design_multisine(o);
    ASSERT_EQ(m.u_V.size(), 400u * 3u * 2u);
    const std::set<std::size_t> excited(m.lines.begin(), m.lines.end());
    for (std::size_t r = 0; r < 2; ++r) {
      const auto X = dft(m.u_V.data() + r * 3 * 400, 400);
      EXPECT_NEAR(X[0].real() / 2.0, 1.5, 1e-12);  // offset (DC reads 2 x with this scaling)
      const double a = m.line_amplitude_V[r];
      for (std::size_t k = 1; k < X.size(); ++k) {
        if (excited.count(k)) {
          EXPECT_NEAR(std::abs(X[k]), a, 1e-10 * a) << k;
        } else {
          EXPECT_LT(std::abs(X[k]), 1e-10 * a) << k;
        }
      }
      // Each line's phase as drawn: cos(2 pi k n / N + phi) reads a e^{j phi} at line k.
      for (std::size_t i = 0; i < m.lines.size(); ++i) {
        const std::complex<double> want = std::polar(a, m.phase_rad[r * m.lines.size() + i]);
        EXPECT_LT(std::abs(X[m.lines[i]] - want), 1e-10 * a) << "line " << m.lines[i];
      }
      // RMS about the offset as asked: A sqrt(F / 2).
      double ss = 0.0;
      for (std::size_t n = 0; n < 400; ++n) ss += std::pow(m.u_V[r * 1200 + n] - 1.5, 2);
      EXPECT_NEAR(std::sqrt(ss / 400.0), 2.0, 1e-10);
    }
  }
}

TEST(Multisine, APeriodOfPrimeLengthIsDesignedAsWell) {
  // 401 ticks: no FFT of its own length is fast, so the lines are summed; the spectrum is the same.
  MultisineOptions o = small();
  o.period_samples = 401;
  const Multisine m = design_multisine(o);
  ASSERT_EQ(m.u_V.size(), 401u * 3u * 2u);
  for (std::size_t r = 0; r < 2; ++r) {
    const auto X = dft(m.u_V.data() + r * 3 * 401, 401);
    for (std::size_t i = 0; i < m.lines.size(); ++i) {
      const std::complex<double> want = std::polar(m.line_amplitude_V[r], m.phase_rad[r * m.lines.size() + i]);
      EXPECT_LT(std::abs(X[m.lines[i]] - want), 1e-10 * m.line_amplitude_V[r]) << "line " << m.lines[i];
    }
  }
}

TEST(Multisine, LineSetsFollowTheChoice) {
  MultisineOptions o = small();
  const auto all = multisine_lines(o);
  EXPECT_EQ(all.front(), 4u);  // 100 Hz / 25 Hz
  EXPECT_EQ(all.back(), 120u);
  EXPECT_EQ(all.size(), 117u);
  o.lines = MultisineLines::odd;
  const auto odd = multisine_lines(o);
  EXPECT_EQ(odd.front(), 5u);
  for (std::size_t k : odd) EXPECT_EQ(k % 2, 1u);
  EXPECT_EQ(odd.size(), 58u);
  o.lines = MultisineLines::log;
  o.lines_per_decade = 20.0;
  const auto lg = multisine_lines(o);
  EXPECT_EQ(lg.front(), 4u);
  EXPECT_EQ(lg.back(), 120u);
  EXPECT_TRUE(std::is_sorted(lg.begin(), lg.end()));
  EXPECT_EQ(std::adjacent_find(lg.begin(), lg.end()), lg.end());
  // 1.48 decades x 20, less the duplicates the rounding makes at low lines.
  EXPECT_GT(lg.size(), 20u);
  EXPECT_LE(lg.size(), 31u);
  // Log-spaced: the lower half of the band holds more lines than the upper half.
  const auto lower = std::count_if(lg.begin(), lg.end(), [](std::size_t k) { return k < 62; });
  EXPECT_GT(lower, static_cast<long>(lg.size()) - lower);
}

TEST(Multisine, PeriodicWithinARealisationNewPhasesAcross) {
  const Multisine m = design_multisine(small());
  for (std::size_t r = 0; r < 2; ++r)
    for (std::size_t p = 1; p < 3; ++p)
      for (std::size_t n = 0; n < 400; ++n)
        ASSERT_EQ(m.u_V[(r * 3 + p) * 400 + n], m.u_V[r * 3 * 400 + n]) << r << " " << p << " " << n;
  double diff = 0.0;
  for (std::size_t n = 0; n < 400; ++n) diff = std::max(diff, std::abs(m.u_V[n] - m.u_V[1200 + n]));
  EXPECT_GT(diff, 0.1);
  // Seeded: the same seed gives the same record, another seed another one.
  EXPECT_EQ(design_multisine(small()).u_V, m.u_V);
  MultisineOptions o = small();
  o.seed = 8;
  EXPECT_NE(design_multisine(o).u_V, m.u_V);
}

TEST(Multisine, PeakAmplitudeBoundsEveryRealisation) {
  MultisineOptions o = small();
  o.amplitude_mode = MultisineAmplitude::peak;
  o.amplitude_V = 3.0;
  o.realisations = 3;
  const Multisine m = design_multisine(o);
  for (std::size_t r = 0; r < 3; ++r) {
    double peak = 0.0;
    for (std::size_t n = 0; n < 400; ++n) peak = std::max(peak, std::abs(m.u_V[r * 1200 + n] - 1.5));
    EXPECT_NEAR(peak, 3.0, 1e-12);
  }
}

TEST(Multisine, RefusesBadOptionsNamingTheField) {
  auto field_of = [](MultisineOptions o) -> std::string {
    try {
      design_multisine(o);
    } catch (const ParameterError& e) {
      return e.field();
    }
    return "";
  };
  MultisineOptions o = small();
  o.sample_rate_Hz = 0.0;
  EXPECT_EQ(field_of(o), "sample_rate_Hz");
  o = small(), o.f_max_Hz = 50.0;
  EXPECT_EQ(field_of(o), "f_max_Hz");
  o = small(), o.f_min_Hz = 6000.0, o.f_max_Hz = 7000.0;
  EXPECT_EQ(field_of(o), "f_min_Hz");
  o = small(), o.f_min_Hz = 101.0, o.f_max_Hz = 110.0;  // no 25 Hz line between
  EXPECT_EQ(field_of(o), "f_min_Hz");
  o = small(), o.amplitude_V = -1.0;
  EXPECT_EQ(field_of(o), "amplitude_V");
  o = small(), o.periods = 0;
  EXPECT_EQ(field_of(o), "periods");
  o = small(), o.realisations = 0;
  EXPECT_EQ(field_of(o), "realisations");
  o = small(), o.period_samples = 2;
  EXPECT_EQ(field_of(o), "period_samples");
  o = small(), o.lines = MultisineLines::log, o.lines_per_decade = 0.0;
  EXPECT_EQ(field_of(o), "lines_per_decade");
}

}  // namespace
}  // namespace hystloop
