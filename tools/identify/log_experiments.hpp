#pragma once
// The identification experiments a live loop ran (hystloop-ctl experiment, e.g.
// --banning-series), cut out of its LCM log: which samples belong to which experiment.
//
// The log holds the requests (<rig>CONTROL START_EXPERIMENT / STOP_EXPERIMENT), the command
// ticks (<rig>COMMAND blocks, mode EXPERIMENT per tick while one runs) and the sensor ticks
// (<rig>SENSOR blocks). The compensator runs the requested sines back to back from the first
// experiment tick on a schedule that is a function of the requests alone (experiment_schedule,
// common/loop/experiment.hpp); after the last one it holds the last voltage in its tracking
// mode until it has the measured sample of the end, so:
//  - each run of consecutive EXPERIMENT ticks is explained by the requests logged before its
//    end, in order; a run that ends inside an experiment was stopped (or the compensator
//    restarted): that experiment is cut short, and the requests still queued were dropped;
//  - every experiment is checked against its commands: the commanded feedforward must be the
//    requested sine at every logged tick (so a request missing from the log, which would shift
//    the schedule, is found, not silently mislabelled);
//  - an experiment is usable when it ran to its end and no tick is SAFE_STATE / SENSOR_FAULT.
//    A frequency-response experiment (at or above rate_independent_below_Hz) must also have a
//    sample for every tick and at most max_not_as_commanded of them LATE_COMMAND, SATURATED or
//    SLEW_LIMITED: its time base and its input's spectrum matter. A slower one is a hysteresis
//    loop, a function of the voltage applied, which every sample records: held (late) or
//    slew-limited commands do not spoil it, and it may lack up to max_missing of its ticks (the
//    bridge skips a tick when it overruns; the stage moves on continuously).
// "settle" experiments are kept and labelled: identification uses only the measured ones.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "ident/sample_csv.hpp"
#include "loop/experiment.hpp"

namespace hystloop {

struct ExperimentLogOptions {
  std::string control_channel = "HX_CONTROL";
  std::string command_channel = "HX_COMMAND";
  std::string sensor_channel = "HX_SENSOR";
  std::string compensator_process = "compensator";  // requests addressed to it (or to everyone) count
  double dt_s = 1e-4;                               // the rig's tick [s]
  double max_not_as_commanded = 0.02;               // fraction of a fast experiment's samples, in [0, 1]
  double max_missing = 0.01;                        // fraction of a slow experiment's ticks, in [0, 1]
  double rate_independent_below_Hz = 10.0;          // BanningFitOptions::frequency_threshold_Hz
  int axis = 0;           // whose samples and commands: an experiment is the ticks this axis's commands mark as one
  void validate() const;  // throws ParameterError naming the field
};

struct LoggedExperiment {
  std::int64_t request_id = 0;
  ExperimentSpec spec;          // as requested; spec.settle for "settle"
  std::int64_t begin_tick = 0;  // [begin, end): the command ticks of this experiment
  std::int64_t end_tick = 0;
  bool complete = false;             // ran to its last period
  std::size_t missing = 0;           // ticks without a sample in the log
  std::size_t safe_state = 0;        // samples flagged SAFE_STATE
  std::size_t sensor_fault = 0;      // ... SENSOR_FAULT
  std::size_t not_as_commanded = 0;  // ... LATE_COMMAND, SATURATED or SLEW_LIMITED
  std::string problem;               // why it cannot be used; empty = usable
  SampleTable samples;               // t = (seq - begin_tick) * dt [s], u = applied [V], y [m]
  bool usable() const noexcept { return problem.empty(); }
};

struct LoggedExperiments {
  std::vector<LoggedExperiment> experiments;  // in the order they ran
  std::vector<std::string> notes;             // what else was found: dropped requests, unexplained ticks
  std::size_t files = 0;
  std::size_t requests = 0;           // distinct START_EXPERIMENT requests for the compensator
  std::size_t blocks = 0;             // runs of EXPERIMENT command ticks
  std::int64_t first_sample_seq = 0;  // of the record's first sample: t = 0 of --from/--to (LogTimeBase::seq)
};

// Reads the files in order as one record. Throws SampleLogError (log_samples.hpp) for a file
// that cannot be read or a log without any experiment tick; ParameterError for bad options.
LoggedExperiments read_logged_experiments(const std::vector<std::string>& files, const ExperimentLogOptions& options);

// Distinct START_EXPERIMENT requests for the compensator in the files, read without keeping any
// sample (a cheap look before deciding whether a log holds several experiments); 0 for a file
// that cannot be read (the reader that follows says why).
std::size_t count_experiment_requests(const std::vector<std::string>& files, const ExperimentLogOptions& options);

// A table, one line per experiment, and the notes.
std::string describe(const LoggedExperiments& logged);

// For a user who has to pick one (a log with several experiments, none chosen): a table of every
// experiment, its index, kind (sine, or settle: not for fitting), offset, amplitude,
// frequency, duration and its time range in the record [s after the first sample, as --from/--to
// count], usable or why not.
std::string list_experiments(const LoggedExperiments& logged, const ExperimentLogOptions& options);

}  // namespace hystloop
