#pragma once
// `hystloop-ctl watch`: the tracking error of the running loop, per second. The bridge records
// each tick's reference and measured position in HX_SENSOR, so a tick's error y_ref - y comes
// from its sensor block alone; ticks without a reference (NaN) have none. With a simulated
// stage the bridge also publishes the true position (HX_SIM_TRUTH), and watch gives the error
// against it beside the measured one, whose sensor noise is the floor.

#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hystloop/sensor_block_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/sim_truth_t.hpp"

namespace hystloop::ctl {

// Tracking errors: how many, the sum of their squares, the largest magnitude.
struct ErrorStats {
  std::uint64_t count = 0;
  double sum_sq_m2 = 0.0;
  double max_abs_m = 0.0;

  void add(double e_m) noexcept;
  std::optional<double> rms_m() const noexcept;  // none without an error
};

// What one second of watching saw.
struct WatchSecond {
  std::uint64_t samples = 0;                     // sensor ticks
  std::uint64_t commands = 0;                    // command ticks
  ErrorStats error;                              // y_ref - y of the sensor ticks with a reference
  ErrorStats true_error;                         // y_ref - y_true of those with their true position too
  std::optional<std::int32_t> buffer_min_ticks;  // lowest buffer depth of an armed sensor block

  // Every tick of the block's `axis` (its error where it has a reference; nothing when the block
  // lacks the axis), and its buffer depth when no tick is SAFE_STATE. Allocation-free.
  void add_sensor_block(const sensor_block_t& block, std::size_t axis = 0) noexcept;
};

// Pairs each HX_SIM_TRUTH block with the HX_SENSOR block of the same seq, in either arrival
// order (the two channels are not ordered against each other), and adds the true error
// y_ref - y_true of every tick with a reference to the second. A block waits for its partner
// among the last kWaiting of its channel; one whose partner never comes (a lost message) is
// dropped with them, so the true figures may cover fewer ticks than the measured ones.
class TruthPairing {
 public:
  static constexpr std::size_t kWaiting = 64;
  explicit TruthPairing(std::size_t axis = 0) noexcept : axis_(axis) {}  // the axis paired (0: x)
  void add_sensor_block(const sensor_block_t& block, WatchSecond& into);
  void add_truth_block(const sim_truth_t& truth, WatchSecond& into);

 private:
  struct Block {
    std::int64_t seq = 0;
    std::vector<double> y_m;  // the references (sensor) or the true positions (truth)
  };
  static void pair(const std::vector<double>& y_ref, const std::vector<double>& y_true, WatchSecond& into) noexcept;
  static void keep(std::deque<Block>& waiting, Block block);
  std::size_t axis_ = 0;
  std::deque<Block> refs_, truths_;
};

struct WatchLine {
  double elapsed_s = 0.0;
  WatchSecond second;
  std::optional<std::int32_t> params_in_use;  // from the commands
  std::optional<std::int32_t> params_latest;  // last HX_PARAMS version seen
  std::optional<std::int64_t> late_total;     // bridge status
  std::optional<std::int64_t> late_delta;     // since the previous bridge report
  std::string bridge_state;                   // "" when no bridge status yet
  std::optional<std::int64_t> clamped_per_s;  // bridge status: ticks clamped (range or slew) in its last second
  // Compensator status, when it learns a periodic reference: RMS error of the last learned period
  // [nm] and the periods learned.
  std::optional<double> learning_rms_nm;
  std::optional<std::int64_t> learning_periods;
  // Compensator status: trajectories it refused, and those it took shaped to the actuator's
  // limits, since it started; shown once either is non-zero.
  std::optional<std::int64_t> trajectories_refused;
  std::optional<std::int64_t> trajectories_shaped;
};

// The compensator's learning error [nm] on `axis` from its counter learning_rms_nm, or
// learning_rms_pm (finer); another axis's behind its name (y_learning_rms_pm).
std::optional<double> learning_rms_nm(const service_status_t& compensator, int axis = 0);
// A compensator counter of `axis`: `name` for x, "y_" + name for y, "z_" + name for z.
std::string axis_counter(std::string_view name, int axis);

// " 12 s  rms   27.9 nm  max   80.1 nm  [true 0.55 nm max 3.1 nm]  ticks 10000/10000  params v3  late 0 (+0)  clamped
// 0/s  buf min 212
//  bridge HEALTHY" and, when the compensator reports learning, "  learned 12.3 nm (34 periods)",
// and when it refused or shaped a trajectory, "  trajectories refused 1, shaped 2"
std::string format_watch_line(const WatchLine& line);

}  // namespace hystloop::ctl
