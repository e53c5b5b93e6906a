#include "ident/banning_experiments.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "core/errors.hpp"

namespace hystloop {

std::string_view to_string(BanningExperimentKind kind) noexcept {
  switch (kind) {
    case BanningExperimentKind::offset: return "offset";
    case BanningExperimentKind::small_amplitude: return "small_amplitude";
    case BanningExperimentKind::amplitude: return "amplitude";
    case BanningExperimentKind::frequency: return "frequency";
  }
  return "unknown";
}

void BanningPlanOptions::validate() const {
  require_positive("sample_rate_Hz", sample_rate_Hz);
  for (double v : offsets_V) require_finite("offsets_V", v);
  require_positive("offset_amplitude_V", offset_amplitude_V);
  for (double v : small_amplitudes_V) require_positive("small_amplitudes_V", v);
  for (double v : amplitudes_V) require_positive("amplitudes_V", v);
  require_positive("hysteresis_frequency_Hz", hysteresis_frequency_Hz);
  if (measure_periods < 1) throw ParameterError("measure_periods", "must be >= 1");
  require_positive("settle_frequency_Hz", settle_frequency_Hz);
  require_positive("slew_V_per_s", slew_V_per_s);
  if (settle_periods < 0) throw ParameterError("settle_periods", "must be >= 0");
  require_non_negative("settle_path_V", settle_path_V);
  for (double f : frequencies_Hz) require_in_range("frequencies_Hz", f, 1e-3, 0.45 * sample_rate_Hz);
  require_positive("frequency_amplitude_V", frequency_amplitude_V);
  require_non_negative("frequency_settle_s", frequency_settle_s);
  require_positive("frequency_measure_s", frequency_measure_s);
}

namespace {

// offset + A sin(phase), the phase advancing at f_settle for the settle periods and then at f.
BanningExperiment sine_experiment(BanningExperimentKind kind, double offset, double amplitude, double f,
                                  double settle_f, double settle_periods, double measure_periods, double fs) {
  BanningExperiment e;
  e.kind = kind;
  e.offset_V = offset;
  e.amplitude_V = amplitude;
  e.frequency_Hz = f;
  e.sample_rate_Hz = fs;
  const auto n_settle = static_cast<std::size_t>(std::llround(settle_periods / settle_f * fs));
  const auto n_measure = static_cast<std::size_t>(std::llround(measure_periods / f * fs));
  e.u.resize(n_settle + n_measure);
  const double two_pi = 2.0 * std::numbers::pi;
  for (std::size_t k = 0; k < n_settle; ++k) {
    e.u[k] = offset + amplitude * std::sin(two_pi * settle_f * static_cast<double>(k) / fs);
  }
  for (std::size_t k = 0; k < n_measure; ++k) {
    e.u[n_settle + k] = offset + amplitude * std::sin(two_pi * f * static_cast<double>(k) / fs);
  }
  e.measure_begin = n_settle;
  e.settle_frequency_Hz = settle_f;
  e.settle_periods = settle_periods;
  e.measure_periods = measure_periods;
  return e;
}

}  // namespace

std::vector<BanningExperiment> plan_banning_experiments(const BanningPlanOptions& o) {
  o.validate();
  std::vector<BanningExperiment> plan;
  const double fh = o.hysteresis_frequency_Hz, fs = o.sample_rate_Hz;
  const double mp = o.measure_periods;
  // Settling cycles: settle_periods, and at least settle_path_V of input path (4 A per period):
  // Coleman-Hodgdon forgets where it came from as exp(-alpha * path), so a small loop after a
  // large one needs many more cycles than a large one (1 V: 100 periods for 400 V).
  auto sp_for = [&](double amplitude) {
    return std::max<double>(o.settle_periods, std::ceil(o.settle_path_V / (4.0 * amplitude) - 1e-9));
  };
  // The settling sine within 90 % of the slew limit: 2 pi f A <= 0.9 slew.
  auto settle_f_for = [&](double amplitude) {
    return std::min(o.settle_frequency_Hz, 0.9 * o.slew_V_per_s / (2.0 * std::numbers::pi * amplitude));
  };
  for (double off : o.offsets_V) {
    plan.push_back(sine_experiment(BanningExperimentKind::offset, off, o.offset_amplitude_V, fh,
                                   settle_f_for(o.offset_amplitude_V), sp_for(o.offset_amplitude_V), mp, fs));
  }
  for (double a : o.small_amplitudes_V) {
    plan.push_back(
        sine_experiment(BanningExperimentKind::small_amplitude, 0.0, a, fh, settle_f_for(a), sp_for(a), mp, fs));
  }
  for (double a : o.amplitudes_V) {
    plan.push_back(sine_experiment(BanningExperimentKind::amplitude, 0.0, a, fh, settle_f_for(a), sp_for(a), mp, fs));
  }
  for (double f : o.frequencies_Hz) {
    if (2.0 * std::numbers::pi * f * o.frequency_amplitude_V > o.slew_V_per_s) {
      throw ParameterError("frequency_amplitude_V", "at " + std::to_string(f) + " Hz needs more than the slew limit " +
                                                        std::to_string(o.slew_V_per_s) + " V/s");
    }
    // Settle and measure at the drive frequency itself: the stage's transient needs
    // frequency_settle_s, the hysteresis (on a live stage, coming from the previous experiment's
    // loop) settle_periods.
    plan.push_back(sine_experiment(BanningExperimentKind::frequency, 0.0, o.frequency_amplitude_V, f, f,
                                   std::max(std::ceil(o.frequency_settle_s * f), sp_for(o.frequency_amplitude_V)),
                                   std::ceil(o.frequency_measure_s * f), fs));
  }
  return plan;
}

std::vector<double> run_on_stage(const BanningStageParams& params, const BanningExperiment& e, double noise_rms_m,
                                 std::uint64_t seed) {
  BanningStage stage(params);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<double> y(e.u.size());
  if (e.u.empty()) return y;
  stage.reset(e.u.front());
  const double dt = 1.0 / e.sample_rate_Hz;
  for (std::size_t k = 0; k < e.u.size(); ++k) {
    y[k] = stage.step(e.u[k], dt) + (noise_rms_m > 0.0 ? noise_rms_m * noise(rng) : 0.0);
  }
  return y;
}

}  // namespace hystloop
