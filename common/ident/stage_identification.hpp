#pragma once
// From a periodic record of a stage to its linear model: the FRF with its uncertainty
// (frequency_response.hpp) and the rational fit with delay (stage_fit.hpp), with the two steps
// between them that every caller needs (hystloop-identify --model stage, hystloop.identify_stage):
//   - a bridge measures y_k at the end of tick k, which is the conventional hold's sample k + 1:
//     one tick earlier than the zero-order hold the fit models. Delaying the data by that tick
//     (z^-1, exact on the lines) makes the fitted delay the rig's own (LinearStageSpec::delay_s),
//     which may be under a tick;
//   - the fit's chi-square expectation needs the degrees of freedom of sigma^2: 2 (R - 1) for the
//     robust method's sigma_total, 2 R (P - 1) for sigma_noise alone.

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ident/frequency_response.hpp"
#include "ident/stage_fit.hpp"

namespace hystloop {

struct StageIdentification {
  FrequencyResponse frf;  // as fitted (moved by the end-of-tick sample where that applies)
  StageFitResult fit;     // status solver_failure with frf's reason when there was no FRF
  // The uncertainty the fit weighted with: sigma_total when realisations measured it, else sigma_noise.
  const std::vector<double>& sigma() const noexcept { return frf.total_available ? frf.sigma_total : frf.sigma_noise; }
  bool ok() const noexcept { return frf.ok() && fit.ok(); }
  // What failed, with its step named ("no frequency response: ...", "no stage model: ...").
  std::string reason() const;
};

// "NUM/DEN" (0 <= NUM <= DEN, DEN >= 1) or "auto" into the options' orders; throws
// ParameterError("order") for anything else.
void set_stage_order(std::string_view order, StageFitOptions& options);

// Degrees of freedom of the FRF's sigma^2 (0: too few to use, the fit then takes sigma as exact).
double sigma_degrees_of_freedom(const FrequencyResponse& frf) noexcept;

// u [V], y [m] laid out as estimate_frequency_response wants. The options' zoh_sample_rate_Hz
// says whether the data were held and sampled (> 0: they were, at that rate); with
// sampled_at_tick_end the data are moved by a tick as above. sigma_dof is set from the FRF.
// Throws ParameterError for bad options; bad data come back as !ok() with a reason.
StageIdentification identify_stage_dynamics(std::span<const double> u, std::span<const double> y,
                                            std::span<const std::size_t> lines, const FrfOptions& frf_options,
                                            StageFitOptions fit_options, bool sampled_at_tick_end);

// How far up the fitted model is known: from the first line at or above from_hz, the lines'
// relative bound
//   (|G - M| + 2 sigma) / |M|,   G the measured response, M the model as the data were fitted,
// stays within `within` up to the returned frequency [Hz] (the last line before the first that
// exceeds it; the highest line when none does; 0 when the first does). A model known within 0.3
// makes the plant a learning update sees 1 +- 0.3 there, well inside its bound
// (loop/periodic_learner.hpp). Near an anti-resonance the measured gain falls into the noise and
// the bound grows: the band ends there. from_hz: where the question starts (hystloop-identify:
// where learning is allowed anyway, 0.7 of the lowest lightly damped mode; the lowest lines of a
// hysteretic stage are its loop's, not the linear model's).
inline constexpr double kStageKnownWithin = 0.3;
double model_known_to_hz(const StageIdentification& id, double from_hz, double within = kStageKnownWithin);

}  // namespace hystloop
