#pragma once
// Nonparametric FRF of a stage from a periodic multisine record (models/multisine.hpp), by the "robust
// method" of Pintelon & Schoukens (System Identification, 2nd ed., sec. 3.7 and 4.3): per
// realisation the DFT of u and y at the excited lines, averaged over the periods after the
// transient ones; G_r = Y_r / U_r; the noise variance from the period-to-period spread; across the
// realisations the mean G and its total variance, noise plus the nonlinear distortion (which
// changes with every phase draw, so it shows up as spread between realisations and not between
// periods). Each line thus carries G, sigma_noise and sigma_total; sigma_total^2 well above
// sigma_noise^2 says the stage is not linear at this drive level.
//
// Record layout (as design_multisine): sample n of period p of realisation r at (r P + p) N + n,
// realisations one after the other in time. The first transient_periods of every realisation are
// dropped (the switch of phases restarts a transient). DFT scaling X(k) = (2/N) sum_n x[n]
// exp(-j 2 pi k n / N), so a cosine of amplitude A on line k reads |X(k)| = A.
//
// What a test can hold the estimate to (white output noise of standard deviation s_v per sample,
// noise-free input of amplitude A per line, a linear system G0, P periods used, R realisations,
// F lines):
//   - one period's output DFT carries circular complex noise with E|V|^2 = 4 s_v^2 / N; the mean
//     of P periods 4 s_v^2 / (N P); u is exact, so G_r = G0 + V / U is unbiased and
//       sigma_G^2 = E|G - G0|^2 = 4 s_v^2 / (N P R A^2)                                     (1)
//   - |G - G0|^2 / sigma_G^2 is exponential with mean 1 (chi^2_2 / 2): its mean over F lines is
//     1 +- 1/sqrt(F), and max over the lines exceeds c^2 with probability ~ F exp(-c^2)
//     (c = 4.5, F = 600: 1e-6). |G| is biased by at most sigma_G^2 / (2 |G0|) (Rice): negligible
//     at a usable SNR.
//   - sigma_noise^2 is unbiased with 2 R (P - 1) real degrees of freedom: per line its relative
//     standard deviation is 1/sqrt(R (P - 1)), the mean over F lines of sigma_noise^2 / (1)
//     1 +- 1/sqrt(F R (P - 1)).
//   - sigma_total^2 (R >= 2) is unbiased with 2 (R - 1) degrees of freedom: the mean over F lines
//     of sigma_total^2 / (1) is 1 +- 1/sqrt(F (R - 1)) for a linear system; a weight 1 / sigma^2
//     from it has mean nu / (nu - 2) (nu = 2 (R - 1)) times 1 / (1), which the fit's chi-square
//     accounts for (stage_fit.hpp).
// The variance of G_r also carries an input-noise term (a measured u): to first order
//   var G_r = |G_r|^2 (var Y / |Y|^2 + var U / |U|^2 - 2 Re(cov(Y, U) / (Y conj U))),
// each from the period-to-period spread; with an exact u this is var Y / |U|^2.

#include <complex>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "ident/fit_status.hpp"

namespace hystloop {

struct FrfOptions {
  double sample_rate_Hz = 1e4;
  std::size_t period_samples = 2000;  // N
  std::size_t periods = 4;            // P in the record, per realisation (transient ones included)
  std::size_t realisations = 1;       // R
  std::size_t transient_periods = 1;  // dropped at the start of every realisation
  void validate() const;              // throws ParameterError naming the field (>= 2 periods must remain)
};

struct FrequencyResponse {
  std::vector<std::size_t> lines;         // DFT line k of each entry
  std::vector<double> frequency_Hz;       // k fs / N
  std::vector<std::complex<double>> G;    // mean over the realisations [y unit / V]
  std::vector<double> sigma_noise;        // standard deviation of G from noise (of the mean)
  std::vector<double> sigma_total;        // noise + nonlinear distortion (of the mean); R = 1: = sigma_noise
  std::vector<double> coherence;          // |sum_b Y conj U|^2 / (sum_b |U|^2 sum_b |Y|^2) over all used periods
  std::vector<double> input_amplitude_V;  // |U| averaged over the realisations
  std::vector<double> output_snr;         // |Y| / its noise standard deviation (period mean), averaged over R
  std::size_t periods_used = 0, realisations = 0;
  bool total_available = false;  // R >= 2: sigma_total measured (else a copy of sigma_noise)
  // Mean over the lines of sigma_total^2 / sigma_noise^2: ~1 for a linear stage (spread
  // 1/sqrt(F (R - 1))), above it when the drive excites the nonlinearity.
  double distortion_ratio = 1.0;
  FitStatus status = FitStatus::solver_failure;
  std::string reason;
  bool ok() const noexcept { return status == FitStatus::ok; }
};

// u, y: R * P * N samples each (layout above); lines: the excited DFT lines (0 < k < N / 2).
// Never throws for bad data (size_mismatch, non_finite_data, constant_input when a line's input is
// zero, out_of_range for a line index beyond Nyquist); throws ParameterError for bad options.
FrequencyResponse estimate_frequency_response(std::span<const double> u, std::span<const double> y,
                                              std::span<const std::size_t> lines, const FrfOptions& options);

}  // namespace hystloop
