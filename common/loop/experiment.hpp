#pragma once
// An identification experiment: a sine on the actuator's voltage, run by the compensator
// instead of the feedforward, for a whole number of periods; or a periodic random-phase
// multisine (models/multisine.hpp) that measures the stage's linear dynamics. The schedule
// functions below reproduce from a log which ticks each experiment of a series took
// (tools/identify).
//
// The multisine on the wire (control_t, whose fields are those of a sine: a new field would change
// the message's fingerprint and every log recorded so far would no longer decode). The fields that
// fit keep their meaning:
//   experiment_amplitude_V  rms of u - offset (or its peak, with amplitude=peak)
//   experiment_offset_V     offset [V]
//   experiment_frequency_Hz f_max, the band's top [Hz]
//   experiment_duration_s   the length of one period [s]: the frequency resolution is its inverse;
//                           a whole number of ticks
// and the rest is a small grammar in `experiment`: the word "multisine" then key=value words
// separated by spaces, each at most once, in any order:
//   f_min=HZ (required, > 0, < f_max)  periods=P (4, >= 3: the first is the transient's)
//   realisations=R (1)  seed=S (1)  amplitude=rms|peak (rms)  lines=all|odd (all)
//   ramp=S (one period; >= 0): the fade-in before and fade-out after the record
// e.g. "multisine f_min=5 periods=4 realisations=3 seed=7". format_multisine_kind writes it.
//
// The voltage is designed once, at start (prepare_experiment, on the compensator's I/O thread as the
// request arrives), never per tick: an inverse FFT per realisation (models/multisine.hpp) and a
// pass over the record. That work must end well inside the horizon the bridge holds (50 ms): the
// sum over the lines that came before the FFT outlasted it at 24 realisations of 5 periods of 2000
// ticks and tripped the bridge's watchdog. A period whose length has a large prime factor still
// sums its lines, F N per realisation, and can outlast it the same way. The record:
//   [ramp-in: L ticks] [R realisations x P periods x N ticks: design_multisine's record] [ramp-out: L]
// The ramps fade the periodic signal in from the offset and out to it with a raised cosine (no
// step: a real stage's resonance would ring). Where one realisation gives way to the next (new
// phases) its first period cross-fades from the previous one's periodic continuation with the same
// window: that period is the transient the estimate drops (ident/frequency_response.hpp), and the
// record keeps design_multisine's layout for every period after it.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace hystloop {

// The multisine's parameters beyond the fields of a sine (the grammar above).
struct MultisineExperiment {
  double f_min_hz = 0.0;  // > 0, below frequency_hz (f_max)
  std::size_t periods = 4;
  std::size_t realisations = 1;
  std::uint64_t seed = 1;
  bool peak = false;     // amplitude_V is the peak of u - offset, not its rms
  bool odd = false;      // odd lines only
  double ramp_s = -1.0;  // < 0: one period
};

// The multisine's voltage at the loop's tick, designed once; shared (read only) by the copies of a
// spec, so a queue and a dry run copy no samples.
struct MultisineSamples {
  double dt_s = 0.0;
  std::size_t period_samples = 0;  // N
  std::size_t ramp_samples = 0;    // L, before and after the record
  std::size_t record_samples = 0;  // R P N
  std::vector<std::size_t> lines;  // excited DFT lines k: frequency k / (N dt)
  std::vector<double> u_V;         // L + R P N + L ticks
};

// u(t) = offset + amplitude * sin(2 pi f (t - start)), run for a whole number of periods.
// `settle` only labels the segment: the same sine, run to bring the hysteresis to its
// stationary loop, whose samples identification skips (Banning's series).
// `multisine`: the multisine above (frequency_hz is f_max, duration_s the period's length); its
// samples come from prepare_experiment.
struct ExperimentSpec {
  double amplitude_V = 250.0;
  double offset_V = 0.0;
  double frequency_hz = 10.0;  // the MEM paper's identification input: 250 sin(20 pi t)
  double duration_s = 2.0;     // rounded up to whole periods
  bool settle = false;
  bool multisine = false;
  MultisineExperiment ms{};
  std::shared_ptr<const MultisineSamples> samples{};  // multisine: set by prepare_experiment
  void validate() const;
};

// The most ticks a multisine may take (ramps included): 8 MB of voltage.
inline constexpr std::size_t kMaxMultisineSamples = 1'000'000;

// The experiment a START_EXPERIMENT request names: kind "sine", "settle" (the same sine,
// labelled), or the multisine grammar above. Validated; throws ParameterError ("experiment" for
// another kind or a malformed multisine word).
ExperimentSpec make_experiment_spec(std::string_view kind, double amplitude_V, double offset_V, double frequency_hz,
                                    double duration_s);
// The `experiment` string of a multisine (the grammar above; periods and realisations always
// written, the other defaults left out).
std::string format_multisine_kind(const MultisineExperiment& ms);
// A multisine: designs its samples at the tick dt_s (off the per-tick path: it allocates). A sine:
// nothing to do. Throws ParameterError: "experiment_duration_s" when a period is not a whole number
// of ticks, "experiment" when f_max reaches Nyquist, the band holds no line, or it is too long.
void prepare_experiment(ExperimentSpec& spec, double dt_s);
// The voltage an experiment commands t_s after its start [V]. A multisine not prepared commands
// its offset.
double experiment_voltage(const ExperimentSpec& spec, double t_s) noexcept;
// Loop time [s] at which an experiment started at start_s ends: after its whole periods (a
// multisine: after its last ramp tick; one not prepared ends at once).
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
