#pragma once
// The experiments of Banning et al. (2001), Section 4 / 5.2-5.3: stationary sines
// u = offset + A sin(2 pi f t) sampled at the bridge rate.
//   offsets      several offsets at a moderate amplitude: the loop centres give a (Theorem 3)
//   small amps   small amplitudes: the loop slope tends to b (Theorem 2, (21))
//   amplitudes   several amplitudes: the loop areas give alpha through (24)
//   frequencies  a small amplitude at several frequencies: the magnitude (27) gives k, c
// Each hysteresis experiment first cycles at settle_frequency_Hz (rate independence: the loop
// converges per period, not per second) and then runs measure_periods slow periods, slow so the
// stage's phase lag adds no area. Only the measured part is handed to the fit. The frequency
// experiments settle too (the stage's transient and the hysteresis'), at their own frequency.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "models/banning_stage.hpp"

namespace hystloop {

enum class BanningExperimentKind { offset, small_amplitude, amplitude, frequency };
std::string_view to_string(BanningExperimentKind kind) noexcept;

struct BanningPlanOptions {
  double sample_rate_Hz = 1e4;
  std::vector<double> offsets_V{-100.0, -50.0, 0.0, 50.0, 100.0};
  double offset_amplitude_V = 20.0;
  std::vector<double> small_amplitudes_V{1.0, 2.0, 3.0, 5.0};
  std::vector<double> amplitudes_V{25.0, 50.0, 100.0, 150.0, 200.0};
  double hysteresis_frequency_Hz = 1.0;  // slow: the stage lag at 1 Hz adds < 0.2 % area
  int measure_periods = 2;
  double settle_frequency_Hz = 50.0;
  int settle_periods = 20;
  // ... and at least this much input path (4 A per period) [V]: on a live stage each experiment
  // starts from the previous one's state, which Coleman-Hodgdon forgets as exp(-alpha * path)
  // (Table 1: alpha = 0.0123 1/V, so 400 V leave e^-5 of it).
  double settle_path_V = 400.0;
  std::vector<double> frequencies_Hz{20.0,   100.0,  300.0,  600.0,  900.0,  1200.0, 1400.0, 1550.0,
                                     1650.0, 1700.0, 1750.0, 1800.0, 1900.0, 2100.0, 2400.0, 2800.0};
  double frequency_amplitude_V = 2.0;
  double frequency_settle_s = 0.03;  // the stage decays as e^{-c t / 2}: 30 ms is e^{-30}
  double frequency_measure_s = 0.1;
  // The actuator's slew limit (the bridge's actuator.slew_V_per_s): a settling sine runs slower
  // where its amplitude would need more than 90 % of it (200 V at 50 Hz needs 6.3e4 V/s).
  double slew_V_per_s = 5.0e4;

  void validate() const;  // throws ParameterError naming the field
};

struct BanningExperiment {
  BanningExperimentKind kind = BanningExperimentKind::offset;
  double offset_V = 0.0;
  double amplitude_V = 0.0;
  double frequency_Hz = 0.0;  // of the measured part
  double sample_rate_Hz = 1e4;
  std::vector<double> u;          // the whole input [V], settling included
  std::size_t measure_begin = 0;  // first sample of the stationary, measured part
  // The same input as two whole-period sines, for a live rig (hystloop-ctl experiment
  // --banning-series): settle_periods at settle_frequency_Hz, then measure_periods at frequency_Hz.
  double settle_frequency_Hz = 0.0;
  double settle_periods = 0.0;
  double measure_periods = 0.0;
};

std::vector<BanningExperiment> plan_banning_experiments(const BanningPlanOptions& options = {});

// Runs one experiment on a simulated stage (reset at the input's first value) and returns y [m]
// for every input sample, with seeded white sensor noise of the given RMS.
std::vector<double> run_on_stage(const BanningStageParams& stage, const BanningExperiment& experiment,
                                 double noise_rms_m, std::uint64_t seed);

}  // namespace hystloop
