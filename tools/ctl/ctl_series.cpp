#include "ctl_series.hpp"

#include <spdlog/fmt/fmt.h>

#include "core/errors.hpp"

namespace hystloop::ctl {

namespace {

ExperimentRequest sine(const char* kind, double offset_V, double amplitude_V, double frequency_Hz, double periods) {
  // The compensator rounds the duration up to whole periods: exactly these.
  return sine_experiment(offset_V, amplitude_V, frequency_Hz, periods / frequency_Hz, kind);
}

}  // namespace

ExperimentSpec to_spec(const ExperimentRequest& r) {
  const std::string kind = r.kind == "multisine" ? format_multisine_kind(r.multisine) : r.kind;  // as on the wire
  return make_experiment_spec(kind, r.amplitude_V, r.offset_V, r.frequency_Hz, r.duration_s);
}

std::vector<SeriesStep> banning_series(const BanningPlanOptions& plan) {
  std::vector<SeriesStep> steps;
  const std::vector<BanningExperiment> experiments = plan_banning_experiments(plan);
  for (std::size_t i = 0; i < experiments.size(); ++i) {
    const BanningExperiment& e = experiments[i];
    const std::string head =
        fmt::format("{} experiment: offset {:g} V, amplitude {:g} V", to_string(e.kind), e.offset_V, e.amplitude_V);
    if (e.settle_periods > 0) {
      steps.push_back({i,
                       head + fmt::format(": settling, {:g} periods at {:g} Hz ({:.3g} s)", e.settle_periods,
                                          e.settle_frequency_Hz, e.settle_periods / e.settle_frequency_Hz),
                       sine("settle", e.offset_V, e.amplitude_V, e.settle_frequency_Hz, e.settle_periods)});
    }
    steps.push_back({i,
                     head + fmt::format(": measuring {:g} periods at {:g} Hz ({:.3g} s)", e.measure_periods,
                                        e.frequency_Hz, e.measure_periods / e.frequency_Hz),
                     sine("sine", e.offset_V, e.amplitude_V, e.frequency_Hz, e.measure_periods)});
  }
  for (const auto& s : steps) s.request.validate();
  if (steps.size() > ExperimentQueue::kCapacity + 1) {
    throw ParameterError("banning-series", fmt::format("{} experiments (settling included) exceed what the compensator "
                                                       "queues ({}): give fewer offsets, amplitudes or frequencies",
                                                       steps.size(), ExperimentQueue::kCapacity + 1));
  }
  return steps;
}

ExperimentRequest mem_paper_experiment(double duration_s) {
  ExperimentRequest r;
  r.kind = "sine";
  r.amplitude_V = 250.0;
  r.frequency_Hz = 10.0;
  r.duration_s = duration_s;
  r.validate();
  return r;
}

double series_duration_s(const std::vector<SeriesStep>& steps) {
  double start = 0.0;
  for (const auto& s : steps) start = experiment_end_s(start, to_spec(s.request));
  return start;
}

SeriesTracker::SeriesTracker(const std::vector<SeriesStep>& steps, double dt_s) : dt_s_(dt_s) {
  require_positive("dt", dt_s);
  for (const auto& s : steps) specs_.push_back(to_spec(s.request));
}

std::optional<std::size_t> SeriesTracker::on_command(std::int64_t seq, bool experiment_mode) {
  if (finished_ || ended_early_) return std::nullopt;
  if (!first_tick_) {
    if (!experiment_mode) return std::nullopt;
    first_tick_ = seq;
    ticks_ = experiment_schedule(seq, specs_, dt_s_);
  }
  if (specs_.empty() || seq >= ticks_.back().end) {
    finished_ = true;
    return std::nullopt;
  }
  if (!experiment_mode) {
    ended_early_ = true;
    return std::nullopt;
  }
  // Commands may be lost on the way to us: report the latest step this tick is in.
  std::optional<std::size_t> entered;
  while (next_step_ < ticks_.size() && seq >= ticks_[next_step_].begin) entered = next_step_++;
  return entered;
}

}  // namespace hystloop::ctl
