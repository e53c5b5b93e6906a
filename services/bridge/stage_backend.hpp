#pragma once
// What the bridge drives: one small interface, so that hardware plugs in beside the
// simulators (see services/bridge/README.md). The real-time thread calls step() once per
// tick; it must not allocate, lock, log or block longer than a fraction of the period.

#include <cstdint>
#include <limits>
#include <array>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "bridge/bridge_settings.hpp"
#include "loop/multi_axis_stage.hpp"
#include "loop/simulated_stage.hpp"

namespace hystloop {

struct StageReading {
  double y_m = 0.0;  // measured position [m]
  // A simulator's true position [m] (y_m without the sensor noise); NaN for hardware, which
  // cannot know it. Published on HX_SIM_TRUTH when finite.
  double y_true_m = std::numeric_limits<double>::quiet_NaN();
  std::int32_t flags = 0;  // sample_flags bits the backend adds (kSimulated, a sensor fault, ...)
  bool go_safe = false;    // the backend asks for the safe state (e.g. its sensor failed too often in a row):
                           // the bridge disarms as for DISARM (ramp to actuator.safe_u_V; re-arm via ARM)
};

class StageBackend {
 public:
  virtual ~StageBackend() = default;
  // Applies u [V] over [t, t + dt] and returns the position measured at its end (a stage of
  // several axes: to x, the others holding their last voltage).
  virtual StageReading step(double u_V, double t_s, double dt_s) noexcept = 0;
  // The axes it drives on one clock (1..kMaxAxes).
  virtual int axes() const noexcept { return 1; }
  // Applies u_V[i] to axis i over [t, t + dt] and writes the axes' readings at its end to out[i];
  // both hold axes() entries. What the bridge's clock thread calls; a one-axis stage's is step().
  virtual void step_axes(std::span<const double> u_V, double t_s, double dt_s, std::span<StageReading> out) noexcept {
    out[0] = step(u_V[0], t_s, dt_s);
  }
  // "sim", "ro", ... (logged and reported in HX_STATUS).
  virtual const std::string& name() const noexcept = 0;
  // Stage gain relative to its start (1 for hardware: unknown), for the status detail.
  virtual double gain_scale() const noexcept { return 1.0; }
  // True when the stage has no wall clock of its own (a simulator): ticks the clock thread
  // could not run on time are then run late, back to back, instead of being skipped.
  virtual bool simulated() const noexcept { return false; }
  // The safe-state hook: leave axis i's actuator at safe_u_V[i] [V] (axes() entries) and keep it there without further
  // step() calls. Called on the real-time thread once the stop's ramp has reached safe_u_V (the
  // last step() applied it), and again after the real-time thread ended and when the bridge is
  // destroyed, whatever happened before (then the ramp may not have finished: a hardware backend
  // takes the actuator there the way the device allows, e.g. its own ramp or output disable).
  // May be called more than once; must not throw, allocate or block for long.
  virtual void hold_safe(std::span<const double> safe_u_V) noexcept = 0;
  // The amplifier enable a hardware backend drives (comedi.enable): `on` while the bridge is armed
  // or ramping to the safe voltage, off in the safe state. Called on the real-time thread before
  // each step_axes(); the line follows in that tick's I/O. hold_safe() drops it too.
  virtual void set_output_enabled(bool /*on*/) noexcept {}
  // The backend's own counters (cumulative; read on the I/O thread while step() runs, so kept
  // in atomics), appended to the bridge's HX_STATUS counters.
  virtual void append_counters(std::vector<std::pair<std::string, std::uint64_t>>& /*entries*/) const {}
};

// The built-in simulator (Banning stage or Ramberg-Osgood plant) with noise and drift.
class SimulatedBackend final : public StageBackend {
 public:
  SimulatedBackend(std::string name, const SimulatedStageConfig& config);
  StageReading step(double u_V, double t_s, double dt_s) noexcept override;
  const std::string& name() const noexcept override { return name_; }
  double gain_scale() const noexcept override { return stage_.gain_scale(); }
  bool simulated() const noexcept override { return true; }
  // A simulated stage has no output stage that could keep driving it: nothing to do.
  void hold_safe(std::span<const double> /*safe_u_V*/) noexcept override {}

 private:
  std::string name_;
  SimulatedStage stage_;
};

// The built-in XY(Z) stage (MultiAxisStage): per axis the simulator above, with its own noise
// seed, and the coupling matrix on the outputs.
class MultiAxisSimulatedBackend final : public StageBackend {
 public:
  MultiAxisSimulatedBackend(std::string name, const MultiAxisStageConfig& config);
  StageReading step(double u_V, double t_s, double dt_s) noexcept override;
  int axes() const noexcept override { return stage_.axes(); }
  void step_axes(std::span<const double> u_V, double t_s, double dt_s, std::span<StageReading> out) noexcept override;
  const std::string& name() const noexcept override { return name_; }
  double gain_scale() const noexcept override;
  bool simulated() const noexcept override { return true; }
  void hold_safe(std::span<const double> /*safe_u_V*/) noexcept override {}

 private:
  std::string name_;
  MultiAxisStage stage_;
  std::array<double, kMaxAxes> u_last_V_{};  // what step() holds the axes other than x at
};

// The backend `name` names: "sim" (Banning), "ro" (Ramberg-Osgood) or "series"; the plant kind in
// `config` is set from the name. Throws ParameterError("bridge.backend") otherwise.
std::unique_ptr<StageBackend> make_stage_backend(const std::string& name, SimulatedStageConfig config);

// The backend bridge.backend names: sim, ro, series (an XY(Z) stage of them when bridge.axes > 1), or comedi
// (ComediBackend: opens the card; throws ConfigError for a config the card refuses, std::runtime_error when it cannot
// be opened).
std::unique_ptr<StageBackend> make_stage_backend(const BridgeSettings& settings);

}  // namespace hystloop
