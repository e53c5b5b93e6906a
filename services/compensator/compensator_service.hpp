#pragma once
// hystloop-compensator: one I/O thread. Each HX_SENSOR block is observed tick by tick and
// answered in its handler with HX_COMMAND blocks for every tick not yet planned up to the
// horizon ahead (Compensator::plan); HX_TRAJECTORY, HX_PARAMS and HX_CONTROL change the
// reference, the MEM parameters, the mode and the experiments. The commands are a
// deterministic function of the messages received, in order: no wall clock reaches the
// control law (a sample's utime only maps a trajectory's start time to loop time).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "compensator/compensator_settings.hpp"
#include "core/latency_stats.hpp"
#include <array>

#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "lcm/channels.hpp"
#include "lcm/publisher.hpp"
#include "lcm/subscription.hpp"
#include "loop/compensator.hpp"
#include "runtime/control_filter.hpp"
#include "runtime/counter_set.hpp"
#include "runtime/status_reporter.hpp"

namespace hystloop {

CompensatorCounters& operator+=(CompensatorCounters& a, const CompensatorCounters& b) noexcept;

// The compensator's own counters (cumulative; RESET_COUNTERS reports them from a baseline).
struct CompensatorServiceCounters {
  std::uint64_t command_blocks_published = 0;
  std::uint64_t command_ticks_published = 0;
  std::uint64_t params_invalid = 0;      // valid = false: diagnostic sets, never used
  std::uint64_t params_stale = 0;        // version not above the last one offered
  std::uint64_t params_refused = 0;      // failed the compensator's own validation
  std::uint64_t trajectories = 0;        // applied
  std::uint64_t trajectory_repeats = 0;  // same version again (UDP repeats)
  std::uint64_t trajectory_refused = 0;
  std::uint64_t trajectory_late_start = 0;  // start time already past: started now instead
  std::uint64_t control_acted = 0;
  std::uint64_t control_refused = 0;
  std::uint64_t bridge_restarts = 0;     // sample seq went back: the control law was restarted
};

class CompensatorService {
 public:
  CompensatorService(const CompensatorSettings& settings, lcm::LCM& lcm, const ChannelNames& channels);

  // Runs until SIGINT/SIGTERM, SHUTDOWN or compensator.run_seconds. Returns 0, or 1 on LCM errors.
  int run();

  // The handlers, public so that tests can drive the service without a network.
  void on_sensor(const sensor_block_t& msg, std::int64_t recv_utime) noexcept;
  void on_trajectory(const trajectory_t& msg);
  void on_params(const mem_params_t& msg);
  void on_control(const control_t& msg);
  void report(std::int64_t utime, bool stopping);

  const Compensator& compensator() const noexcept { return *compensator_; }
  const CompensatorServiceCounters& counters() const noexcept { return counters_; }
  // The last command block published (tests look at it).
  const command_block_t& last_command() const noexcept { return command_; }

 private:
  void apply_trajectory(const TrajectorySpec& spec, std::int64_t start_utime);
  void publish_plan() noexcept;
  void restart_control_law();
  CounterSet::Entries collect_counters() const;

  CompensatorSettings settings_;
  lcm::LCM& lcm_;
  std::optional<Compensator> compensator_;
  Publisher<command_block_t> command_pub_;
  command_block_t command_{};                       // storage reserved
  std::array<CommandTick, command_block_t::MAX_TICKS> plan_{};
  Subscription<sensor_block_t> samples_;
  Subscription<trajectory_t> trajectories_;
  Subscription<mem_params_t> params_;
  Subscription<control_t> control_;
  ControlFilter filter_{"compensator"};
  StatusReporter status_;

  // What maps utime to loop time, and a trajectory whose start time needs it.
  bool have_sample_ = false;
  std::int64_t last_sample_utime_ = 0;
  std::optional<TrajectorySpec> pending_trajectory_;  // a timed start that arrived before the first sample
  std::int64_t pending_start_utime_ = 0;
  std::int64_t trajectory_version_ = 0;
  std::int32_t offered_version_ = 0;  // highest mem_params_t.version offered

  CompensatorServiceCounters counters_;
  CompensatorCounters retired_{};  // counted by control laws a bridge restart replaced
  LatencyStats latency_;  // sensor block received (LCM's receive time) -> its answer published [ns]
  LatencyStats work_;     // handler work per sensor block [ns]
  LatencyStats latency_total_;
  std::uint64_t blocks_in_period_ = 0;
  std::uint64_t swaps_reported_ = 0;
  CounterSet reported_;
};

}  // namespace hystloop
