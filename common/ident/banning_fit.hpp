#pragma once
// Banning et al. (2001) identification recipe, Section 4 with Theorem 3:
//   a      least-squares line through the loop centres (u_centre, y_centre = a u_centre)
//   b      seeded by the mean loop slope at small amplitude (Theorem 2: slope -> b)
//   alpha  seeded from the small-amplitude area 4/3 (a - b) alpha A^3, then (b, alpha) refined
//          jointly by Ceres on the exact closed forms (21) for every slope and (24) for the areas
//          of the larger-amplitude experiments (relative residuals)
//   k, c   the magnitude h(w) of every fast experiment from the first harmonic of y (robust at a
//          few samples per period, where a sampled peak-to-peak is not), through (27) with the
//          slope (21) at the drive amplitude, fitted by Ceres to the stage's magnitude response.
//          The bridge samples a zero-order-held input, so by default the model is the exact ZOH
//          discretisation of (28)-(29) at the data's sample rate; zoh_magnitude = false fits the
//          continuous |G(jw)| as the paper does (5 % apart at the 1.7 kHz resonance, 10 kHz).
//   lag    not in the paper, whose loops are slow enough for the stage to be static. A loop read
//          through a lag phi gains phi * (closed integral of dw/dtheta du/dtheta) of area (pi
//          slope A^2 phi for a line); a lead takes as much. The bridge's simulated sensor, read at
//          the end of each held sample, leads by half a sample less the stage's lag (~33 us):
//          at 4 Hz 1-2 % of the areas, enough to pull alpha 5 % low. The magnitude experiments' phases
//          below f_n / 2, less the identified stage's, give the rest of the lag as a delay (plus a
//          constant, the small loop's own phase); each loop's area is then corrected by the lag at
//          its frequency (stage plus delay) on the identified loop, and (b, alpha) and (k, c) are
//          fitted once more.
// Each experiment's offset, amplitude and frequency are read from its input, so the data need
// no labels: slow experiments (< frequency_threshold_Hz) are loops, fast ones are magnitudes.

#include <complex>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "ident/fit_clock.hpp"
#include "ident/fit_status.hpp"
#include "models/banning_stage.hpp"
#include "models/loop_features.hpp"

namespace hystloop {

struct BanningExperimentData {
  std::span<const double> u;  // [V], stationary part only
  std::span<const double> y;  // [m]
  double sample_rate_Hz = 1e4;
  // The excitation's frequency when it is known (e.g. from the logged request of a live
  // experiment); 0 = estimate it from u. Offset and amplitude are always fitted to u.
  double frequency_Hz = 0.0;
};

struct BanningFitOptions {
  double frequency_threshold_Hz = 10.0;  // slower: hysteresis loop experiment; faster: magnitude
  // Slopes up to here seed b; areas are used above it (an amplitude read within 1 % of it counts
  // as at it: noise must not move a loop from one set to the other).
  double small_amplitude_max_V = 5.0;
  double min_offset_span_V = 1.0;                           // the centres must span this much to give a
  BanningOrder order = BanningOrder::kHysteresisThenStage;  // how (27) is inverted
  bool zoh_magnitude = true;
  bool correct_lag = true;  // correct the loop areas for the measured lag (needs magnitude experiments)
  LoopFeatureOptions loop{};
  double max_solver_time_s = 1.0;  // per Ceres solve, read from `clock`
  FitClock clock{};                // empty = monotonic; fixed_fit_clock() for a reproducible fit

  void validate() const;  // throws ParameterError naming the field
};

struct BanningPoint {
  double offset_V = 0.0;     // read from u
  double amplitude_V = 0.0;  // read from u (first harmonic)
  double frequency_Hz = 0.0;
  bool magnitude_experiment = false;
  bool used = false;
  bool area_fitted = false;    // a loop above small_amplitude_max_V: its area is among those alpha is fitted to
  std::string note;            // why an experiment was skipped
  LoopFeatures features{};     // loop experiments
  double lag_rad = 0.0;        // loop experiments: the lag at this frequency, stage and delay (0 if not measured)
  double lag_area = 0.0;       // [m V] loop experiments: the correction for that lag (area + lag_area is fitted)
  double magnitude = 0.0;      // h(w) [-], magnitude experiments
  double response_m = 0.0;     // [m] magnitude experiments: first-harmonic amplitude of y
  double phase_lag_rad = 0.0;  // magnitude experiments: first-harmonic phase of y behind u
};

struct BanningFitResult {
  ColemanHodgdonParams hysteresis{};  // a, b, alpha (s_max kept at its default)
  SecondOrderStageParams stage{};     // k, c (valid only when stage_identified)
  bool stage_identified = false;
  FitStatus status = FitStatus::solver_failure;
  std::string reason;
  std::vector<BanningPoint> points;
  double centre_rms_m = 0.0;        // of the centre line fit
  double slope_rel_rms = 0.0;       // (21) against the measured slopes
  double area_rel_rms = 0.0;        // (24) against the measured areas
  double magnitude_rel_rms = 0.0;   // magnitude model against h(w)
  bool lag_identified = false;      // the areas were corrected for the lag (else lag_note says why not)
  double delay_s = 0.0;             // the lag beyond the stage model, as a delay [s] (sampling, sensor)
  double lag_phase_rms_rad = 0.0;   // residual of the phase fit
  std::size_t lag_experiments = 0;  // magnitude experiments below f_n / 2 that gave it
  std::string lag_note;
  double solve_time_s = 0.0;
  bool ok() const noexcept { return status == FitStatus::ok; }
};

BanningFitResult fit_banning(std::span<const BanningExperimentData> experiments, const BanningFitOptions& options = {});

// Offset, first-harmonic amplitude and frequency of a sampled sine: frequency from the
// interpolated crossings of its mid level (refined, if asked, by minimising the residual of the
// sine fit: interpolation is biased at a few samples per period), amplitude and offset by least
// squares at that frequency.
struct SineEstimate {
  double offset = 0.0, amplitude = 0.0, frequency_Hz = 0.0;
  bool ok = false;
};
SineEstimate estimate_sine(std::span<const double> u, double sample_rate_Hz, bool refine_frequency = true);
// First-harmonic amplitude of y at a known frequency (least squares with a constant).
double first_harmonic_amplitude(std::span<const double> y, double frequency_Hz, double sample_rate_Hz);

// Stage response: continuous k / (k - w^2 + j c w), or its exact ZOH discretisation at sample
// time T (G_d(e^{jwT}), y[n] = x[n]) when T > 0; the magnitude is its modulus.
std::complex<double> stage_response_model(double k, double c, double omega, double sample_time_s) noexcept;
double stage_magnitude_model(double k, double c, double omega, double sample_time_s) noexcept;
// The area a small lag phi [rad] adds to the loop of `h` under u = offset + A sin(theta):
// phi * closed integral of (dw/dtheta)(du/dtheta) dtheta, on the model (exact, rate independent).
// [m V] per rad; pi * b * A^2 for a loop near the line of slope b.
double loop_lag_area_per_rad(const ColemanHodgdonParams& h, double offset_V, double amplitude_V);

}  // namespace hystloop
