#pragma once
// Everything hystloop-compensator is configured with, read from the YAML tree (after --set
// overrides and --params snippets) and validated there: a refused value throws ConfigError
// naming the file and the field. Model sections are read through the models' parameter tables
// (models/model_descriptors.hpp), the names `hystloop-identify --out` writes and hystloop-model
// reads (mem: {c1, c2, c3}, pi: {count, range_V, thresholds, weights}, linear: {gain, offset},
// katalenic: {k1, k2, ..., input_shaping: {...}}).

#include <filesystem>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "loop/compensator.hpp"
#include "loop/trajectory.hpp"
#include "models/gain_plausibility.hpp"
#include "models/model_set.hpp"

namespace hystloop {

struct CompensatorSettings {
  CompensatorConfig control{};      // mode, models, horizon, dt
  TrajectorySpec trajectory{};      // the initial reference (default: hold at 0), started with the first sample
  double run_seconds = 0.0;         // stop after this long; 0 = until SIGINT/SIGTERM/SHUTDOWN
  int sample_queue_capacity = 256;  // LCM's queue for HX_SENSOR [blocks]
  int rt_priority = 0;              // SCHED_FIFO priority 1..99 of the (only) thread; 0 = normal scheduling
  bool lock_memory = false;         // mlockall at start
  // A parameter set (HX_PARAMS, HX_MODEL, or a model section of the file) whose gain leaves
  // [linear.gain / F, linear.gain * F] over the actuator's range is refused (models/gain_plausibility.hpp).
  double plausible_gain_factor = GainPlausibility{}.factor;  // compensator.plausible_gain_factor, F [-]
};

// The band parameter sets are checked against: the configured linear model's gain (the stage's
// mean slope, as the bridge's servo.nominal_gain_m_per_V) within plausible_gain_factor, over the
// actuator's range.
GainPlausibility gain_plausibility(const CompensatorSettings& settings) noexcept;

const std::vector<std::string>& compensator_config_keys();

// Reads and validates; refuses unknown keys. Throws ConfigError naming the field.
CompensatorSettings load_compensator_settings(const Config& config);

// Merges a parameter snippet (as hystloop-identify --out writes it) over `config`, key by key.
// Throws ConfigError naming the snippet file when it cannot be read.
void merge_params_file(Config& config, const std::filesystem::path& snippet);

// One line per section, for the start-up log.
std::vector<std::string> describe(const CompensatorSettings& settings);

}  // namespace hystloop
