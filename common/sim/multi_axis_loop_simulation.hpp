#pragma once
// The loop of an XY(Z) stage in one process, faster than real time: per axis the compensator's
// control law and the bridge's logic (one safe state for the stage: loop/multi_axis_bridge.hpp),
// the simulated multi-axis stage with its coupling (loop/multi_axis_stage.hpp), on one tick
// clock, exchanging samples and commands in blocks as LoopSimulation does for one axis. A path
// (raster, Lissajous) is given to every axis as its share of the decoupled reference
// (loop/scan_path.hpp, ScanShare).

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "loop/compensator.hpp"
#include "loop/multi_axis_bridge.hpp"
#include "loop/multi_axis_stage.hpp"
#include "loop/scan_path.hpp"

namespace hystloop {

struct MultiAxisLoopConfig {
  MultiAxisStageConfig stage = flexure_stage(2);  // its coupling's n() is the number of axes
  std::array<ActuatorLimits, kScanAxes> limits{};
  std::array<CompensatorConfig, kScanAxes> compensator{};  // all with the same dt_s
  std::array<FeedbackGains, kScanAxes> servo{};            // the bridge's servo per axis
  int block_ticks = 10;

  int axes() const noexcept { return stage.axes(); }
};

// One tick of every axis (entries past the stage's axes are 0).
struct MultiAxisTick {
  std::int64_t k = 0;
  double t_s = 0.0;
  AxisPositions u_V{};       // applied
  AxisPositions y_m{};       // measured (sensor noise included)
  AxisPositions y_true_m{};  // the stage's true position per axis, (C s)_j
  AxisPositions y_ref_m{};   // the axis's reference in force (NaN when none): its own r_a, what its sensor must read
  std::array<std::int32_t, kScanAxes> flags{};
};

class MultiAxisLoopSimulation {
 public:
  explicit MultiAxisLoopSimulation(const MultiAxisLoopConfig& config);

  void run(double seconds, const std::function<void(const MultiAxisTick&)>& on_tick = {});

  // A path on every axis (its start_s: the loop time it starts at, at least blend_s after the next
  // tick), axis i following row i of decoupling's C^-1 (AxisCoupling::identity: no decoupling).
  // decoupling.n() must be the stage's axis count (ParameterError "decoupling", never a silent
  // misassignment); an axis's refusal (Compensator::take_scan) names it and no axis takes the path.
  void take_path(const RasterSpec& raster, const AxisCoupling& decoupling, double blend_s);
  void take_path(const LissajousSpec& lissajous, const AxisCoupling& decoupling, double blend_s);

  // A compensator that stops sending one axis's commands (a fault to test the stage's safety). An
  // axis outside 0..kMaxAxes-1 is ignored.
  void drop_commands(int axis, bool drop) noexcept {
    if (axis >= 0 && axis < kMaxAxes) drop_[static_cast<std::size_t>(axis)] = drop;
  }

  int axes() const noexcept { return stage_.axes(); }
  Compensator& compensator(int axis) { return compensators_.at(static_cast<std::size_t>(axis)); }
  MultiAxisBridge& bridge() noexcept { return bridge_; }
  MultiAxisStage& stage() noexcept { return stage_; }
  std::int64_t next_tick() const noexcept { return k_; }
  double now_s() const noexcept { return static_cast<double>(k_) * dt_s_; }
  double dt_s() const noexcept { return dt_s_; }

 private:
  MultiAxisLoopConfig config_;
  double dt_s_;
  MultiAxisBridge bridge_;
  MultiAxisStage stage_;
  std::vector<Compensator> compensators_;
  template <class Path>
  void take(const Path& path, const AxisCoupling& decoupling, double blend_s);

  std::int64_t k_ = 0;
  std::vector<CommandTick> plan_;  // scratch for the compensators' plans
  std::array<BridgeTick, kScanAxes> ticks_{};
  AxisPositions y_last_m_{};
  std::array<bool, kScanAxes> drop_{};
  bool armed_ = false;  // the bridge arms at the first plan
};

}  // namespace hystloop
