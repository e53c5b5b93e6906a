#pragma once
// Random-phase multisine excitation for measuring a stage's linear dynamics (Pintelon & Schoukens,
// System Identification, 2nd ed., ch. 2-4). Why a periodic multisine rather than noise or a sweep:
// an integer number of periods of N samples puts all of its power on the DFT lines k fs / N (no
// leakage, no window), the period-to-period spread of the response then is the noise alone, and
// several realisations (new random phases, same amplitude spectrum) turn the nonlinear distortion
// into a variance that can be measured beside the noise (the "robust method", frequency_response.hpp).
//
//   u[(r P + p) N + n] = offset_V + sum_{k in lines} A_r cos(2 pi k n / N + phi_{r,k})
//
// r = 0..R-1 realisations, p = 0..P-1 periods, n = 0..N-1 samples: realisations follow one another
// in time, each P periods long; the phases phi_{r,k} are uniform on [0, 2 pi) from the seed.
// The amplitude A_r is the same on every line of a realisation: rms_V = A sqrt(F / 2) for F lines;
// with the peak set instead, A_r is chosen so that max_n |u - offset_V| = peak_V in realisation r.
// Units: V for u, Hz for frequencies; line k is the frequency k * sample_rate_Hz / period_samples.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace hystloop {

enum class MultisineLines {
  all,  // every line in [f_min_Hz, f_max_Hz]
  odd,  // odd lines only: even-order distortion then falls on unexcited lines
  log,  // about lines_per_decade lines, log-spaced (denser at low frequency), each line at most once
};
enum class MultisineAmplitude { rms, peak };

struct MultisineOptions {
  double sample_rate_Hz = 1e4;
  std::size_t period_samples = 2000;  // N: the frequency resolution is sample_rate_Hz / N (5 Hz)
  double f_min_Hz = 5.0;              // band; lines strictly between 0 and Nyquist
  double f_max_Hz = 3000.0;
  MultisineLines lines = MultisineLines::all;
  double lines_per_decade = 40.0;  // MultisineLines::log only
  MultisineAmplitude amplitude_mode = MultisineAmplitude::rms;
  double amplitude_V = 1.0;  // rms or peak of u - offset_V, per amplitude_mode
  double offset_V = 0.0;
  std::size_t periods = 4;       // P per realisation (the first may be dropped as a transient)
  std::size_t realisations = 1;  // R, each a new phase draw
  std::uint64_t seed = 1;

  void validate() const;  // throws ParameterError naming the field (also when the band holds no line)
};

struct Multisine {
  std::vector<double> u_V;               // R * P * N samples, layout above
  std::vector<std::size_t> lines;        // excited DFT line indices k (ascending), frequency k fs / N
  std::vector<double> frequency_Hz;      // of each line
  std::vector<double> phase_rad;         // R * lines.size(): phi_{r,k} at [r * lines.size() + i]
  std::vector<double> line_amplitude_V;  // A_r per realisation
  double sample_rate_Hz = 0.0;
  std::size_t period_samples = 0, periods = 0, realisations = 0;
};

// Throws ParameterError (options.validate()).
Multisine design_multisine(const MultisineOptions& options);

// The excited lines alone (what design_multisine puts in `lines`), for a caller that measures a
// record it did not design. Throws ParameterError as design_multisine.
std::vector<std::size_t> multisine_lines(const MultisineOptions& options);

}  // namespace hystloop
