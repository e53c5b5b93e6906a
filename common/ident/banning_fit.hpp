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
// Each experiment's offset, amplitude and frequency are read from its input, so the data need
// no labels: slow experiments (< frequency_threshold_Hz) are loops, fast ones are magnitudes.

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
  double frequency_threshold_Hz = 10.0;                     // slower: hysteresis loop experiment; faster: magnitude
  double small_amplitude_max_V = 5.0;                       // slopes up to here seed b; areas are used above it
  double min_offset_span_V = 1.0;                           // the centres must span this much to give a
  BanningOrder order = BanningOrder::kHysteresisThenStage;  // how (27) is inverted
  bool zoh_magnitude = true;
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
  std::string note;         // why an experiment was skipped
  LoopFeatures features{};  // loop experiments
  double magnitude = 0.0;   // h(w) [-], magnitude experiments
};

struct BanningFitResult {
  ColemanHodgdonParams hysteresis{};  // a, b, alpha (s_max kept at its default)
  SecondOrderStageParams stage{};     // k, c (valid only when stage_identified)
  bool stage_identified = false;
  FitStatus status = FitStatus::solver_failure;
  std::string reason;
  std::vector<BanningPoint> points;
  double centre_rms_m = 0.0;       // of the centre line fit
  double slope_rel_rms = 0.0;      // (21) against the measured slopes
  double area_rel_rms = 0.0;       // (24) against the measured areas
  double magnitude_rel_rms = 0.0;  // magnitude model against h(w)
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

// Stage magnitude: continuous k / sqrt((k - w^2)^2 + (c w)^2), or that of its exact ZOH
// discretisation at sample time T (|G_d(e^{jwT})|) when T > 0.
double stage_magnitude_model(double k, double c, double omega, double sample_time_s) noexcept;

}  // namespace hystloop
