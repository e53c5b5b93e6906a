#pragma once
// What the scan table needs from a log beyond RunData (run_data.hpp): the trajectories sent on
// HX_TRAJECTORY, the requests on HX_CONTROL that change what the loop does (SET_LEARNING,
// SET_MODE, START_EXPERIMENT, DISARM, SHUTDOWN) and the compensator's HX_STATUS reports (its
// verdict on each trajectory, its learning figures, the model it runs). Times are the log's
// receive timestamps, the same clock as RunData's samples.
//
// Senders repeat a request over UDP with the same id (hystloop-ctl: 3 times) and a trajectory
// with the same version: each is kept once, at its first receipt.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "lcm/channels.hpp"

namespace hystloop::report {

struct ScanTrajectory {
  std::int64_t recv_utime = 0;
  std::int64_t version = 0;
  std::string shape;  // "hold", "sine", "cosine", "triangle", "points"
  double amplitude_m = 0.0;
  double offset_m = 0.0;
  double frequency_hz = 0.0;
  double blend_s = 0.0;
  double corner_s = 0.0;  // triangle: as requested (0: the compensator chooses)
  bool shape_to_feasible = false;
  bool periodic() const noexcept;  // sine, cosine or triangle with a frequency > 0
};

// A request on HX_CONTROL that starts a new segment of the run.
struct ScanControl {
  enum class Kind : std::uint8_t { kLearningOff, kLearningOn, kLearningReset, kMode, kExperiment, kStop };
  std::int64_t recv_utime = 0;
  Kind kind = Kind::kStop;
};

// One HX_STATUS report of the compensator: the counters the scan reads, and its detail.
struct ScanCompensatorStatus {
  std::int64_t recv_utime = 0;
  std::string detail;
  std::optional<std::int64_t> trajectory_version, trajectory_refused_version, trajectory_shaped_version;
  std::optional<std::int64_t> learning_active, learning_periods, learning_rms_pm;
  std::optional<std::int64_t> model_switches, params_swapped;
};

struct ScanEvents {
  std::vector<ScanTrajectory> trajectories;  // in log order, one per version
  std::vector<ScanControl> controls;         // in log order, one per request id
  std::vector<ScanCompensatorStatus> compensator;
};

// Reads `files` in order (as read_logs does). Events that do not decode are skipped here: the
// report's reader counts them. Only the trajectories of `axis` (0 x, 1 y, 2 z) are kept: another
// axis's reference is no segment of this one. The compensator reports its learner's figures
// (learning_active, learning_periods, learning_rms_pm) for x alone, so for another axis they are
// left out (the learning state then comes from the SET_LEARNING requests only). Throws
// std::runtime_error naming a file that cannot be opened.
ScanEvents read_scan_events(const std::vector<std::filesystem::path>& files, const ChannelNames& channels,
                            const std::string& compensator_process, int axis = 0);

// The mode in the compensator's detail ("... mode pi, params v3 ..."), "" when none.
std::string compensator_mode(const std::string& detail);

// The compensator's verdict text for trajectory `version` in a detail ("trajectory V refused:
// WHY; ..." -> "WHY"), `what` being refused, shaped or taken; "" when absent.
std::string verdict_text(const std::string& detail, std::int64_t version, const std::string& what);

}  // namespace hystloop::report
