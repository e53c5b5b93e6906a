#pragma once
// Everything hystloop-bridge is configured with, read from the YAML tree (after --set
// overrides) and validated there: a refused value throws ConfigError naming the file and
// the field. Keys carry SI units in their names (see deploy/config/bridge.yaml).

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "bridge/comedi_config.hpp"
#include "core/config.hpp"
#include "loop/bridge_core.hpp"
#include "loop/multi_axis_stage.hpp"
#include "loop/oscillation_detector.hpp"
#include "loop/simulated_stage.hpp"
#include "models/axis_coupling.hpp"

namespace hystloop {

struct RtSettings {
  int ticks_per_wake = 1;    // the clock thread wakes once per this many ticks and runs them back to back
                             // (1 for hardware; the simulator may batch: its stage has no wall clock)
  int priority = 0;          // SCHED_FIFO priority 1..99 of the real-time thread; 0 = normal scheduling
  int io_priority = 0;       // SCHED_FIFO priority of the I/O thread (below `priority`); 0 = normal scheduling
  bool lock_memory = false;  // mlockall at start
  int cpu = -1;              // pin the real-time thread to this CPU; -1 = no pinning
  // SCHED_FIFO and locked memory must be granted, else the bridge refuses to run (exit 1, the fix
  // named): a card's ticks on normal scheduling miss deadlines while the DAC holds stale voltages.
  // Default: on for a hardware backend, off for the simulators; rt.required: false waives it.
  bool required = false;
};

// The simulated XY(Z) stage's default coupling: x moves y by 3 %, and z by 3 % of x and of y, as
// flexure stages show (flexure_stage()).
AxisMatrix default_stage_coupling() noexcept;

// Why the bridge will not run when rt.required and real time was refused (`what`: the refusal),
// with the ways to grant it and to waive it.
std::string real_time_refused(const std::string& what);

struct BridgeSettings {
  std::string backend = "sim";  // sim (Banning stage) | ro (Ramberg-Osgood) | series (plant.*) | comedi (a DAQ card)
  // Axes on the one clock (1..kMaxAxes: x, y, z), each with its actuator limits and servo
  // (limits_of, servo_of), all in one safe state (MultiAxisBridge).
  int axes = 1;
  // The simulated XY(Z) stage's coupling C (models/axis_coupling.hpp): C(j, i) is axis j's output
  // per metre of axis i's own displacement (coupling.x_to_y is C(1, 0)). Only its axes x axes
  // block is used; an AxisCoupling is built from it (validated) when axes > 1.
  AxisMatrix coupling = default_stage_coupling();
  double rate_hz = 10000.0;      // the loop's clock
  SimulatedStageConfig stage{};  // noise, seed, drift and the plants' parameters (the series plant's tick: dt_s())
  ComediSettings comedi{};       // the comedi.* keys (used when backend is comedi)
  ActuatorLimits limits{};       // axis x's (actuator.*), and every other axis's unless it has its own
  FeedbackGains servo{};         // axis x's servo on y_ref - y (servo.*; all gains 0 = feedforward only), likewise
  // Axes y and z with keys of their own (actuator.y.u_max_V, servo.z.kp, ...): axis x's with those
  // keys applied. Empty: the axis is as x. [0] is never set. The watchdog is the stage's: one key,
  // actuator.watchdog_s, for every axis.
  std::array<std::optional<ActuatorLimits>, kMaxAxes> axis_limits{};
  std::array<std::optional<FeedbackGains>, kMaxAxes> axis_servo{};
  int block_ticks = 50;  // ticks per HX_SENSOR block: 200 messages/s (1 = a message per tick)
  RtSettings rt{};
  bool auto_arm = false;                 // arm as soon as commands flow (first arm only)
  double rearm_after_trip_s = 0.0;       // > 0: re-arm this long after a watchdog trip once commands flow (0 = never)
  double stop_ramp_timeout_s = 0.75;     // on every stop, the ramp to actuator.safe_u_V must end within this:
                                         // the longest ramp + kStopRampMargin_s (set from the actuator's keys)
  double degraded_late_fraction = 0.01;  // status DEGRADED above this late fraction over a report period
  double run_seconds = 0.0;              // stop after this long; 0 = until SIGINT/SIGTERM/SHUTDOWN
  int command_queue_capacity = 256;      // LCM's queue for HX_COMMAND [blocks]
  // Commands for ticks further ahead of the bridge's own clock than this are refused: the
  // compensator plans compensator.horizon_s (0.05) ahead of the last sample, which is behind the
  // clock, so 10 ms of margin takes every honest plan and a forged sensor stream moves none.
  double max_lead_s = 0.06;
  // A hardware backend's own clock: ticks whose deadline passed are skipped, and the outputs hold
  // the last voltage meanwhile, whatever the plan and the servo asked. Any skipped tick makes the
  // rig DEGRADED; more than this much time skipped within one second (a single stall, or many
  // short ones) takes every axis to the safe state, ramped, until re-armed. 10 ms: a fifth of the
  // plan's horizon, 20 ms of a 50 Hz line's period.
  double max_stall_s = 0.01;
  // A servo that oscillates (loop/oscillation_detector.hpp): its output's RMS above a corner beyond
  // a bound for a hold time, on any axis, takes every axis to the safe state, ramped, naming the
  // axis and the frequency, until re-armed.
  OscillationLimit oscillation{};

  double dt_s() const noexcept { return 1.0 / rate_hz; }
  // Axis i's actuator and servo (0 <= i < kMaxAxes).
  const ActuatorLimits& limits_of(int axis) const noexcept;
  const FeedbackGains& servo_of(int axis) const noexcept;
  // Every axis's, axes entries: what MultiAxisBridge takes.
  std::array<ActuatorLimits, kMaxAxes> axes_limits() const noexcept;
  std::array<FeedbackGains, kMaxAxes> axes_servo() const noexcept;
  // Axis i's safe voltage, axes entries (StageBackend::hold_safe).
  std::array<double, kMaxAxes> safe_voltages() const noexcept;
  // The stop's ramp: the longest of every axis's (ActuatorLimits::longest_safe_ramp_s).
  double longest_safe_ramp_s() const noexcept;
};

// How long a stop's ramp to actuator.safe_u_V may take beyond the longest one (from the end of
// the range farthest from it at min(safe_ramp, slew)): the real-time thread's next wake-up and a
// busy machine. 250 V at 1e3 V/s: 0.25 s + 0.5 s.
inline constexpr double kStopRampMargin_s = 0.5;

// The built-in XY(Z) stage these settings describe: per axis `stage` with the plant bridge.backend
// names and the noise seed bridge.seed + axis; `coupling`'s axes x axes block.
MultiAxisStageConfig multi_axis_stage(const BridgeSettings& settings);

// Every key the bridge reads (for check_no_unknown_keys and the docs).
const std::vector<std::string>& bridge_config_keys();

// Reads and validates; refuses unknown keys. Throws ConfigError naming the field.
BridgeSettings load_bridge_settings(const Config& config);

// One line per section, for the start-up log.
std::vector<std::string> describe(const BridgeSettings& settings);

}  // namespace hystloop
