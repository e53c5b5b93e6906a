#pragma once
// A series of identification experiments for the compensator to run back to back (control_t
// START_EXPERIMENT requests it queues), and the arithmetic that follows it from the commands.
// Banning et al.'s series: the plan of common/ident/banning_experiments.hpp, each experiment a
// "settle" sine (to reach the stationary loop; identification skips it) then the measured "sine".

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ctl_requests.hpp"
#include "ident/banning_experiments.hpp"
#include "loop/experiment_queue.hpp"

namespace hystloop::ctl {

struct SeriesStep {
  std::size_t experiment = 0;  // index in the plan
  std::string what;            // e.g. "offset -50 V, amplitude 20 V: measuring 2 periods at 1 Hz"
  ExperimentRequest request;
};

// The experiment the compensator runs for a request (throws ParameterError if it would refuse it).
ExperimentSpec to_spec(const ExperimentRequest& request);

// Throws ParameterError for a bad plan, or one with more steps than the compensator queues.
std::vector<SeriesStep> banning_series(const BanningPlanOptions& plan);

// The MEM paper's identification input, u = 250 sin(20 pi t) V, for duration_s (whole periods).
ExperimentRequest mem_paper_experiment(double duration_s);

// Total time of the steps, run back to back [s].
double series_duration_s(const std::vector<SeriesStep>& steps);

// Where a running series is, from the command ticks (HX_COMMAND blocks carry a mode per tick):
// the schedule starts at the first EXPERIMENT tick (the compensator's experiment_schedule). After
// the last experiment the compensator holds its voltage in the tracking mode: a tick past the
// series' end in any mode finishes it.
class SeriesTracker {
 public:
  SeriesTracker(const std::vector<SeriesStep>& steps, double dt_s);
  // The command tick `seq`, in tick order; returns the index of a step that this tick starts
  // (in order, each once), if any.
  std::optional<std::size_t> on_command(std::int64_t seq, bool experiment_mode);
  bool started() const noexcept { return first_tick_.has_value(); }
  bool finished() const noexcept { return finished_; }
  // True once a non-experiment command arrived before the series' last tick.
  bool ended_early() const noexcept { return ended_early_; }
  std::int64_t end_tick() const noexcept { return ticks_.empty() ? 0 : ticks_.back().end; }
  std::optional<std::int64_t> first_tick() const noexcept { return first_tick_; }

 private:
  std::vector<ExperimentSpec> specs_;
  double dt_s_;
  std::vector<ExperimentTicks> ticks_;
  std::optional<std::int64_t> first_tick_;
  std::size_t next_step_ = 0;
  bool finished_ = false;
  bool ended_early_ = false;
};

}  // namespace hystloop::ctl
