#pragma once
// The whole control loop in one process, faster than real time: the bridge's logic (jitter
// buffer, servo, safety), the simulated stage and the compensator, exchanging samples and
// commands as the services do over LCM — samples in blocks of block_ticks, each block
// answered by the commands planned through the horizon — with time as an argument. Used by
// the tracking tests and the tracking benchmark; the services run the same classes.

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "loop/bridge_core.hpp"
#include "loop/compensator.hpp"
#include "loop/simulated_stage.hpp"

namespace hystloop {

struct LoopSimulationConfig {
  SimulatedStageConfig stage{};
  ActuatorLimits limits{};
  CompensatorConfig compensator{};
  FeedbackGains servo{};  // the bridge's servo (all zero: feedforward only)
  int block_ticks = 10;   // samples reach the compensator in blocks of this many ticks
};

// One tick as the loop saw it.
struct LoopTick {
  std::int64_t k = 0;
  double t_s = 0.0;
  double u_V = 0.0;        // applied
  double y_m = 0.0;        // measured (with sensor noise)
  double y_true_m = 0.0;   // the stage's true position
  double y_ref_m = 0.0;    // reference for this tick (NaN when none)
  std::int32_t flags = 0;  // sample flags from the bridge
  std::int32_t params_version = 0;
};

// Tracking error statistics over a window of ticks with a reference.
struct TrackingStats {
  std::size_t n = 0;
  double rms_measured_m = 0.0;  // against the noisy sensor, as a real rig would report it
  double rms_true_m = 0.0;      // against the true position: what the stage really did
  double max_abs_true_m = 0.0;
};

class LoopSimulation {
 public:
  explicit LoopSimulation(const LoopSimulationConfig& config);

  // Runs `seconds` of loop time; `on_tick` (optional) sees every tick. Returns nothing;
  // ticks are also kept in history() when keep_history is on.
  void run(double seconds, const std::function<void(const LoopTick&)>& on_tick = {});

  Compensator& compensator() noexcept { return compensator_; }
  BridgeCore& bridge() noexcept { return bridge_; }
  SimulatedStage& stage() noexcept { return stage_; }
  std::int64_t next_tick() const noexcept { return k_; }
  double now_s() const noexcept { return static_cast<double>(k_) * dt_s_; }

  void keep_history(bool on) { keep_history_ = on; }
  const std::vector<LoopTick>& history() const noexcept { return history_; }

  // Tracking error over history ticks with t in [from_s, to_s) that have a reference.
  TrackingStats tracking(double from_s, double to_s) const;

 private:
  LoopSimulationConfig config_;
  double dt_s_;
  BridgeCore bridge_;
  SimulatedStage stage_;
  Compensator compensator_;
  std::int64_t k_ = 0;
  bool keep_history_ = true;
  std::vector<LoopTick> history_;
  std::vector<CommandTick> plan_;  // scratch for the compensator's plan
  double y_last_m_ = 0.0;
  bool armed_ = false;  // the bridge arms at the first plan
};

}  // namespace hystloop
