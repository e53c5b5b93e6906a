#pragma once
// A continuous-time rational model with an input delay, G(s) = N(s) / D(s) e^{-s tau}, fitted to a
// measured FRF with its uncertainty (frequency_response.hpp), weighted by 1 / sigma per line.
//
// Method: Sanathanan-Koerner (SK) iterations on polynomials in the scaled s~ = s / w_s
// (w_s = 2 pi f_max of the data), D(s~) = 1 + d1 s~ + ... + dn s~^n, N(s~) = b0 + ... + bm s~^m,
// followed by a Ceres (Levenberg-Marquardt) refinement of every coefficient and tau on the exact
// weighted residual sum_k |G_k - M(j w_k)|^2 / sigma_k^2. Why SK and not vector fitting:
//   - any (numerator, denominator) order, in particular the relative degree 2 of a stage
//     (m = n - 2), and the unit DC gain as the linear constraint b0 = d0 = 1; vector fitting's
//     partial fractions give m = n - 1 or n and need extra constraints for both;
//   - the conditioning that argues for vector fitting is a problem of wide bands and high orders.
//     Measured on the two-mode test stage (orders 2/4, 600 lines 5 Hz - 3 kHz): the SK
//     least-squares matrix has condition 6.9e13 with s in rad/s, 22 with s scaled by w_s, 3.5 with
//     its columns equilibrated too (sk_condition); nothing left for partial fractions to gain;
//   - both converge to the same SK fixed point (Hendrickx & Dhaene 2006); SK takes 5 iterations on
//     the test stage at order 4 (misfitting lower orders may cycle; the iterations are capped at
//     sk_iterations and the refinement starts from the last). Neither fixed point is the weighted
//     least-squares optimum, and with a hold SK sees only a corrected version of the data: the
//     refinement moves the test stage's poles by 5e-5 (relative) and lowers the weighted cost
//     from 2288 to 836 (600 lines).
// Delay: the SK fit is profiled over tau (a grid on [0, max_delay_s], then Brent on the best
// bracket), tau then refined jointly with the coefficients.
// Sampled data: a bridge holds u (ZOH) and samples y, so the measured FRF is not G(jw) e^{-jw tau}
// but its ZOH discretisation, which adds half a tick of apparent delay, a sinc (-1.3 dB at 3 kHz,
// 10 kHz) and the images of G (the first one ~4 % of |G| at 3 kHz on the test stage). With
// zoh_sample_rate_Hz > 0 the refinement fits the exact ZOH response of the continuous model (in
// closed form per partial fraction, so for simple poles; the delay split across the hold, so tau
// is continuous and need not be a whole tick); SK's seed uses the data divided by the sinc and
// half a tick. The poles, zeros and delay are then the continuous stage's own; fitting sampled
// data as continuous instead leaves chi-square per line ~1000 on the test stage (a test shows it).
// Order: given, or chosen (auto_order) as the lowest denominator order n = 1..max_order (with
// m = max(0, n - relative_degree)) whose chi-square per line is consistent with the uncertainty:
// cost / (F - p / 2) <= chi2_accept * nu / (nu - 2) with p real parameters, F lines, nu the degrees of
// freedom of sigma^2 (E[1 / sigma^2] is nu / (nu - 2) times the true one; nu = 2 (R - 1) for the
// robust method's sigma_total, 0 = known exactly).
// Units: frequency Hz, poles and zeros rad/s, delay s; G in the data's unit (m/V, or 1 normalised).

#include <complex>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "ident/fit_status.hpp"

namespace hystloop {

struct StageFitData {
  std::span<const double> frequency_Hz;     // > 0, ascending not required
  std::span<const std::complex<double>> G;  // measured response
  std::span<const double> sigma;            // standard deviation of each G (E|G - G0|^2 = sigma^2), > 0
};

struct StageFitOptions {
  int numerator_order = 2;    // m (auto_order: ignored)
  int denominator_order = 4;  // n (auto_order: ignored)
  bool auto_order = false;
  int max_order = 8;                // auto_order: largest n tried
  int relative_degree = 2;          // auto_order: m = max(0, n - relative_degree)
  double chi2_accept = 1.5;         // accept (order_consistent) chi2 per line <= this x its expectation
  double sigma_dof = 0.0;           // nu of sigma^2 (> 2), 0 = sigma known exactly
  bool unit_dc_gain = true;         // N(0) / D(0) = 1 (the hysteresis model carries the gain)
  double zoh_sample_rate_Hz = 0.0;  // > 0: data of a held and sampled stage at this rate (above)
  double max_delay_s = 1e-3;        // delay searched in [0, max_delay_s]
  int delay_grid_points = 41;
  int sk_iterations = 30;
  bool refine = true;  // Ceres on the exact weighted residual (and the exact ZOH response)
  int max_refine_iterations = 100;

  void validate() const;  // throws ParameterError naming the field
};

struct StageOrderTrial {
  int numerator_order = 0, denominator_order = 0;
  double chi2_per_line = 0.0;
  bool accepted = false;
};

struct StageFitResult {
  // G(s) = gain prod(s - zeros) / prod(s - poles) e^{-s delay_s}
  std::vector<std::complex<double>> poles_rad_s;
  std::vector<std::complex<double>> zeros_rad_s;
  double gain = 0.0;                // root-locus gain b_m / d_n [data unit (rad/s)^(n-m)]
  double dc_gain = 0.0;             // N(0) / D(0) (1 with unit_dc_gain)
  std::vector<double> numerator;    // ascending powers of s [rad/s]: N(s) = sum numerator[i] s^i
  std::vector<double> denominator;  // ascending, denominator[0] = 1
  double delay_s = 0.0;
  int numerator_order = 0, denominator_order = 0;
  double zoh_sample_rate_Hz = 0.0;  // as fitted (0: continuous data)

  std::vector<std::complex<double>> residual;  // per line: G - model (the ZOH'd model when zoh)
  std::vector<double> weighted_residual;       // |residual| / sigma
  double cost = 0.0;                           // sum of weighted_residual^2
  double chi2_per_line = 0.0;                  // cost / (F - p / 2)
  double chi2_expected = 1.0;                  // nu / (nu - 2), or 1
  // chi2_per_line <= chi2_accept * chi2_expected: the residual is the uncertainty's. With
  // auto_order and no order up to max_order consistent, the result is the lowest-chi-square order,
  // status ok, this false and `reason` says so.
  bool order_consistent = false;
  double sk_condition = 0.0;  // of the last SK least-squares matrix (equilibrated)
  int sk_iterations_used = 0;
  bool refined = false;
  std::vector<StageOrderTrial> orders;  // auto_order: every order tried

  FitStatus status = FitStatus::solver_failure;
  std::string reason;
  bool ok() const noexcept { return status == FitStatus::ok; }

  // G(j 2 pi f) e^{-j 2 pi f delay_s}: the continuous stage.
  std::complex<double> model_response(double f_Hz) const;
  // What a bridge at zoh_sample_rate_Hz measures: the exact ZOH discretisation (with the delay)
  // at e^{j 2 pi f / fs}; model_response when zoh_sample_rate_Hz = 0.
  std::complex<double> sampled_response(double f_Hz) const;
};

// Never throws for bad data (size_mismatch for lengths, non_finite_data, out_of_range for
// sigma <= 0 or a frequency <= 0 or at/above Nyquist of the hold, too_few_samples when the lines
// do not determine the order); the reason names the field. Throws ParameterError for bad options.
StageFitResult fit_stage_model(const StageFitData& data, const StageFitOptions& options = {});

}  // namespace hystloop
