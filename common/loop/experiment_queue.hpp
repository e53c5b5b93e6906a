#pragma once
// Identification experiments run by the compensator, one after another: a running sine and
// the ones waiting behind it (fixed capacity, nothing allocated). Loop time is an argument:
// the first experiment starts at the first time it is asked about; the next starts exactly
// where the previous ended (whole periods), so a series is one continuous input.

#include <array>
#include <cstddef>

#include "loop/experiment.hpp"

namespace hystloop {

class ExperimentQueue {
 public:
  static constexpr std::size_t kCapacity = 128;

  // What the experiments command at loop time t_s.
  struct Step {
    bool active = false;  // an experiment covers t_s: command voltage_V
    bool ended = false;   // the last experiment ended at or before t_s (reported once)
    double voltage_V = 0.0;
  };

  // Starts with the next step() or waits behind the running one. Throws ParameterError
  // ("experiment") when the spec is invalid or kCapacity already wait. A multisine must be
  // prepared (prepare_experiment): step() only reads its samples.
  void add(const ExperimentSpec& spec);
  // Ends the running experiment at loop time end_s (if it started; else drops it) and drops
  // the waiting ones.
  void stop(double end_s) noexcept;
  // Advances to loop time t_s (non-decreasing between calls). Allocation- and throw-free.
  Step step(double t_s) noexcept;

  bool running() const noexcept { return has_running_; }
  std::size_t queued() const noexcept { return queued_; }

 private:
  struct Running {
    ExperimentSpec spec{};
    bool started = false;  // start_s/end_s are set by the first step() it answers
    double start_s = 0.0;
    double end_s = 0.0;
  };
  Running running_{};
  bool has_running_ = false;
  std::array<ExperimentSpec, kCapacity> waiting_{};  // ring
  std::size_t head_ = 0;
  std::size_t queued_ = 0;
};

}  // namespace hystloop
