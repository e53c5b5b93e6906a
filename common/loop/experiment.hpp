#pragma once
// An identification experiment: a sine on the actuator's voltage, run by the compensator
// instead of the feedforward, for a whole number of periods. The schedule functions below
// reproduce from a log which ticks each experiment of a series took (tools/identify).

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace hystloop {

// u(t) = offset + amplitude * sin(2 pi f (t - start)), run for a whole number of periods.
// `settle` only labels the segment: the same sine, run to bring the hysteresis to its
// stationary loop, whose samples identification skips (Banning's series).
struct ExperimentSpec {
  double amplitude_V = 250.0;
  double offset_V = 0.0;
  double frequency_hz = 10.0;  // the MEM paper's identification input: 250 sin(20 pi t)
  double duration_s = 2.0;     // rounded up to whole periods
  bool settle = false;
  void validate() const;
};

// The experiment a START_EXPERIMENT request names: kind "sine", or "settle" (the same sine,
// labelled). Validated; throws ParameterError ("experiment" for another kind).
ExperimentSpec make_experiment_spec(std::string_view kind, double amplitude_V, double offset_V, double frequency_hz,
                                    double duration_s);
// The voltage an experiment commands t_s after its start [V].
double experiment_voltage(const ExperimentSpec& spec, double t_s) noexcept;
// Loop time [s] at which an experiment started at start_s ends: after its whole periods.
double experiment_end_s(double start_s, const ExperimentSpec& spec) noexcept;
// The first tick k whose loop time k * dt_s is at or after t_s: the first command past an
// experiment that ends at t_s. With experiment_end_s this reproduces the compensator's
// schedule from a log (tools/identify splits Banning's series with it).
std::int64_t first_tick_at_or_after(double t_s, double dt_s) noexcept;

// The command ticks [begin, end) of experiments run back to back, the first starting at
// first_tick: what the compensator commands when all of them were given in time.
struct ExperimentTicks {
  std::int64_t begin = 0;
  std::int64_t end = 0;
};
std::vector<ExperimentTicks> experiment_schedule(std::int64_t first_tick, std::span<const ExperimentSpec> specs,
                                                 double dt_s);

}  // namespace hystloop
