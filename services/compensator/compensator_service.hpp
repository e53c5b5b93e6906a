#pragma once
// hystloop-compensator: one I/O thread (the lowest latency: a sample is answered in the
// handler that receives it). HX_SENSOR -> Compensator::update -> HX_COMMAND; HX_TRAJECTORY,
// HX_PARAMS and HX_CONTROL change the reference, the MEM parameters, the mode and the gains.
// The commands are a deterministic function of the messages received, in order: no wall
// clock reaches the control law (a sample's utime only maps a trajectory's start time).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "compensator/compensator_settings.hpp"
#include "core/latency_stats.hpp"
#include "hystloop/actuator_command_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/sensor_sample_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "lcm/channels.hpp"
#include "lcm/publisher.hpp"
#include "lcm/subscription.hpp"
#include "loop/compensator.hpp"
#include "runtime/control_filter.hpp"
#include "runtime/status_reporter.hpp"

namespace hystloop {

// The compensator's own counters (cumulative; RESET_COUNTERS reports them from a baseline).
struct CompensatorServiceCounters {
  std::uint64_t commands_published = 0;
  std::uint64_t params_invalid = 0;      // valid = false: diagnostic sets, never used
  std::uint64_t params_stale = 0;        // version not above the last one offered
  std::uint64_t params_refused = 0;      // failed the compensator's own validation
  std::uint64_t trajectories = 0;        // applied
  std::uint64_t trajectory_repeats = 0;  // same version again (UDP repeats)
  std::uint64_t trajectory_refused = 0;
  std::uint64_t trajectory_late_start = 0;  // start time already past: started now instead
  std::uint64_t control_acted = 0;
  std::uint64_t control_refused = 0;
  std::uint64_t feedback_holds = 0;      // times the bridge entered its safe state (feedback held)
  std::uint64_t bridge_restarts = 0;     // sample seq went back: the control law was restarted
};

class CompensatorService {
 public:
  CompensatorService(const CompensatorSettings& settings, lcm::LCM& lcm, const ChannelNames& channels);

  // Runs until SIGINT/SIGTERM, SHUTDOWN or compensator.run_seconds. Returns 0, or 1 on LCM errors.
  int run();

  // The handlers, public so that tests can drive the service without a network.
  void on_sample(const sensor_sample_t& msg, std::int64_t recv_utime) noexcept;
  void on_trajectory(const trajectory_t& msg);
  void on_params(const mem_params_t& msg);
  void on_control(const control_t& msg);
  void report(std::int64_t utime, bool stopping);

  const Compensator& compensator() const noexcept { return *compensator_; }
  const CompensatorServiceCounters& counters() const noexcept { return counters_; }
  const actuator_command_t& last_command() const noexcept { return command_; }

 private:
  void apply_trajectory(TrajectorySpec spec, std::int64_t start_utime);
  void restart_control_law();
  std::vector<std::pair<std::string, std::uint64_t>> collect_counters() const;

  CompensatorSettings settings_;
  lcm::LCM& lcm_;
  std::optional<Compensator> compensator_;
  Publisher<actuator_command_t> command_pub_;
  actuator_command_t command_{};
  Subscription<sensor_sample_t> samples_;
  Subscription<trajectory_t> trajectories_;
  Subscription<mem_params_t> params_;
  Subscription<control_t> control_;
  ControlFilter filter_{"compensator"};
  StatusReporter status_;

  // Inputs remembered across messages.
  bool have_sample_ = false;
  std::int64_t last_sample_utime_ = 0;
  std::int64_t last_sample_seq_ = -1;
  std::optional<TrajectorySpec> pending_trajectory_;  // arrived before the first sample
  std::int64_t pending_start_utime_ = 0;
  TrajectorySpec trajectory_{};       // the reference in use (for where a new one starts from); none: hold at 0
  std::int64_t trajectory_version_ = 0;
  std::int32_t offered_version_ = 0;  // highest mem_params_t.version offered
  FeedbackGains gains_{};             // as the operator set them
  bool feedback_held_ = false;        // the bridge is in its safe state: feedback output held at 0

  CompensatorServiceCounters counters_;
  LatencyStats latency_;  // sample received (LCM's receive time) -> command published [ns]
  LatencyStats work_;     // handler work per sample [ns]
  LatencyStats latency_total_;
  std::uint64_t samples_in_period_ = 0;
  std::uint64_t swaps_reported_ = 0;
  std::vector<std::pair<std::string, std::uint64_t>> baseline_;
  struct EndpointBaselines {
    EndpointCounters sensor, trajectory, params, control;
    PublisherCounters command;
  } endpoint_base_{};
};

}  // namespace hystloop
