#include "loop/experiment.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "core/errors.hpp"

namespace hystloop {

void ExperimentSpec::validate() const {
  require_positive("experiment.amplitude_V", amplitude_V);
  require_finite("experiment.offset_V", offset_V);
  require_positive("experiment.frequency_hz", frequency_hz);
  require_positive("experiment.duration_s", duration_s);
}

ExperimentSpec make_experiment_spec(std::string_view kind, double amplitude_V, double offset_V, double frequency_hz,
                                    double duration_s) {
  if (kind != "sine" && kind != "settle") {
    throw ParameterError("experiment",
                         "'" + std::string(kind) + "' unknown (sine, or settle: a sine identification skips)");
  }
  const ExperimentSpec spec{amplitude_V, offset_V, frequency_hz, duration_s, kind == "settle"};
  spec.validate();
  return spec;
}

double experiment_voltage(const ExperimentSpec& spec, double t_s) noexcept {
  return spec.offset_V + spec.amplitude_V * std::sin(2.0 * std::numbers::pi * spec.frequency_hz * t_s);
}

double experiment_end_s(double start_s, const ExperimentSpec& spec) noexcept {
  const double periods = std::ceil(spec.duration_s * spec.frequency_hz - 1e-9);
  return start_s + periods / spec.frequency_hz;
}

std::int64_t first_tick_at_or_after(double t_s, double dt_s) noexcept {
  auto k = static_cast<std::int64_t>(std::ceil(t_s / dt_s));
  // The compensator compares static_cast<double>(k) * dt with t: settle the rounding the same way.
  while (k > 0 && static_cast<double>(k - 1) * dt_s >= t_s) --k;
  while (static_cast<double>(k) * dt_s < t_s) ++k;
  return k;
}

std::vector<ExperimentTicks> experiment_schedule(std::int64_t first_tick, std::span<const ExperimentSpec> specs,
                                                 double dt_s) {
  std::vector<ExperimentTicks> ticks;
  ticks.reserve(specs.size());
  double start_s = static_cast<double>(first_tick) * dt_s;  // Compensator::loop_time
  std::int64_t begin = first_tick;
  for (const ExperimentSpec& spec : specs) {
    const double end_s = experiment_end_s(start_s, spec);
    const std::int64_t end = std::max(begin, first_tick_at_or_after(end_s, dt_s));
    ticks.push_back({begin, end});
    begin = end;
    start_s = end_s;
  }
  return ticks;
}

}  // namespace hystloop
