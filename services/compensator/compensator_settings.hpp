#pragma once
// Everything hystloop-compensator is configured with, read from the YAML tree (after --set
// overrides and --params snippets) and validated there: a refused value throws ConfigError
// naming the file and the field. Model sections are read through the models' parameter tables
// (models/model_descriptors.hpp), the names `hystloop-identify --out` writes and hystloop-model
// reads (mem: {c1, c2, c3}, pi: {count, range_V, thresholds, weights}, linear: {gain, offset},
// katalenic: {k1, k2, ..., input_shaping: {...}}).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "loop/compensator.hpp"
#include "loop/scan_path.hpp"
#include "models/axis_coupling.hpp"
#include "loop/trajectory.hpp"
#include "models/gain_plausibility.hpp"
#include "models/model_set.hpp"
#include "runtime/rig_check.hpp"

namespace hystloop {

// A path every axis follows together, taken with the first sensor block (scan.* keys).
struct ScanSettings {
  enum class Path : std::int8_t { kNone, kRaster, kLissajous };
  Path path = Path::kNone;
  RasterSpec raster{};         // its corner_s 0: resonance_corner_s of the stage model (1 ms without one)
  LissajousSpec lissajous{};   //
  double start_after_s = 0.2;  // loop time from the first sample to the path's start [s]
  double blend_s = 0.05;       // the approach from where each axis is [s]
  bool decouple = true;        // each axis its share of C^{-1} r (C: the decoupling keys); false: r alone
};

struct CompensatorSettings {
  // Axes of the stage (1..kMaxAxes), one control law each, every one configured as `control`;
  // sensor blocks of another count are refused. Trajectories, parameter sets and experiments move
  // or model the axis they name (the others keep theirs); modes and learning apply to every axis.
  int axes = 1;
  // The stage's coupling as identified (models/axis_coupling.hpp; decoupling.x_to_y is C(y, x)):
  // a scan gives each axis its share of C^{-1} r. Identity: none known.
  AxisCoupling decoupling{};
  ScanSettings scan{};
  CompensatorConfig control{};      // mode, models, horizon, dt
  TrajectorySpec trajectory{};      // the initial reference (default: hold at 0), started with the first sample
  double run_seconds = 0.0;         // stop after this long; 0 = until SIGINT/SIGTERM/SHUTDOWN
  int sample_queue_capacity = 256;  // LCM's queue for HX_SENSOR [blocks]
  // compensator.trajectory_check: a trajectory's dry runs on the checker's thread (true, the
  // default: a long one never holds up the commands the bridge waits for), or at once on the I/O
  // thread (false: "inline"). Inline, the commands are a deterministic function of the messages in
  // order, as an exact replay needs (tests/data/golden-loop.compensator.yaml); on the thread a
  // trajectory takes effect at the first tick not yet planned when its check ends, which depends
  // on how busy the machine is.
  bool check_on_thread = true;
  int rt_priority = 0;       // SCHED_FIFO priority 1..99 of the (only) thread; 0 = normal scheduling
  bool lock_memory = false;  // mlockall at start
  // A parameter set (HX_PARAMS, HX_MODEL, or a model section of the file) whose gain leaves
  // [linear.gain / F, linear.gain * F] over the actuator's range is refused (models/gain_plausibility.hpp).
  double plausible_gain_factor = GainPlausibility{}.factor;  // compensator.plausible_gain_factor, F [-]
  // The actuator limits the plan keeps inside, each axis's with where it came from: held against
  // the bridge's at run time (runtime/rig_check.hpp).
  std::vector<RigLimitsOwn> rig_limits;
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

// The corners a raster runs with: its own corner_s, else the compensator's choice for `stage`
// (resonance_corner_s; 1 ms without dynamics). One value for every axis of the path.
double raster_corner_s(const RasterSpec& raster, const StageModel& stage) noexcept;

// A scan as one axis's share (ScanShare) of its path starting at loop time start_s: the row of
// C^{-1} (C = `decoupling`) when scan.decouple, else the axis's own reference; a raster's corners
// corner_s (raster_corner_s, settled once for all axes).
ScanShare scan_share(const ScanSettings& scan, const AxisCoupling& decoupling, int axis, double start_s,
                     double corner_s);

// Loop time a scan's check may cost on the compensator's one thread, summed over the axes: each
// axis's share is checked whole by a dry run of its plan (~0.25 us a tick here), while the bridge's
// buffer holds 50 ms of commands. A longer path (or one of more axes) is refused, naming this.
inline constexpr double kScanCheckBudget_s = 6.0;
// The loop time a scan's check covers on every axis: from now to its end (its approach, its path).
double scan_check_s(const ScanSettings& scan, double corner_s) noexcept;

// One line per section, for the start-up log.
std::vector<std::string> describe(const CompensatorSettings& settings);

}  // namespace hystloop
