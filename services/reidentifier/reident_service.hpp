#pragma once
// hystloop-reidentifier's LCM shell around ReidentCore. One I/O thread (the caller of run())
// owns lcm::LCM and the estimator; the refit runs on the core's worker thread.
//
// One process fits one axis of the stage (reidentifier.axis, --axis: x, y or z); a lab runs one
// per axis. Its process name, on <rig>STATUS and as control_t.target, is "reidentifier" for x
// (what every tool and script addresses) and "reidentifier-y" / "reidentifier-z" for the others;
// the sets it publishes carry its axis.
//
//   <rig>SENSOR  -> ReidentCore::on_sensor_block: each tick's applied u_V and measured y_m of our
//                   axis feed the estimator (ticks flagged SAFE_STATE / SENSOR_FAULT skipped and
//                   counted; a block refused as non-finite or out of range poisons the window; a
//                   block without our axis is refused whole, counted, sensor_blocks_wrong_axes)
//   <rig>COMMAND -> ReidentCore::on_command_block: the parameter version the compensator applies
//                   to our axis, by tick (versions seen there are numbered above; status
//                   params_version_applied)
//   <rig>PARAMS  -> sets for our axis only (another axis's: counted, params_other_axis, nothing
//                   else): a newer valid set from someone else becomes the set in use; our echo
//                   ignored; a set with our publisher id and a version we never published is not
//                   used, logged once, counted (params_forged) and DEGRADED on <rig>STATUS (for
//                   30 s after the last one, and while the compensator applies it)
//   <rig>TRAJECTORY, <rig>SCAN -> a new reference for our axis (each request's version once): the
//                   estimator's window starts again (window_restarts), so that no refit is fitted
//                   across two references
//   <rig>CONTROL -> SHUTDOWN and RESET_COUNTERS addressed to our process name (or to all)
//   every 10 ms  -> poll the core: publish an accepted candidate on <rig>PARAMS (valid = true,
//                   residual_m = its held-out RMS); a refused one is counted, logged by the
//                   worker, and published only with publish_invalid, as valid = false
//   every 10 ms  -> with reidentifier.models on: poll the ModelChooser; a model change (or new parameters
//                   of a model other than MEM) goes out on <rig>MODEL (model_params_t)
//   <rig>CONTROL -> SET_MODE addressed to our process name pins the model (hystloop-ctl pin-model): the
//                   mode's model (linear, mem, pi, katalenic), or MODE_OFF = automatic choice again
//   1 Hz         -> <rig>STATUS, under our process name

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "core/latency_stats.hpp"
#include "core/log_limiter.hpp"
#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/model_params_t.hpp"
#include "hystloop/scan_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "lcm/channels.hpp"
#include "lcm/control_filter.hpp"
#include "lcm/publisher.hpp"
#include "lcm/subscription.hpp"
#include "reident/model_chooser.hpp"
#include "reident/reident_core.hpp"
#include "reidentifier/reident_options.hpp"
#include "runtime/control_acks.hpp"
#include "runtime/counter_set.hpp"
#include "runtime/rig_check.hpp"
#include "runtime/status_reporter.hpp"

namespace hystloop {

class ReidentService {
 public:
  static constexpr const char* kProcessName = "reidentifier";  // axis x's: the name tools address

  // "reidentifier" for axis 0 (x), "reidentifier-y", "reidentifier-z" for 1 and 2.
  static std::string process_name(int axis);

  // `rig_limits`: this process's actuator range, refused when the rig's bridge reports another
  // (runtime/rig_check.hpp); empty: not checked.
  ReidentService(lcm::LCM& lcm, const ChannelNames& names, const ReidentOptions& options,
                 std::vector<RigLimitsOwn> rig_limits = {});

  // Serves until SIGINT/SIGTERM or a SHUTDOWN request; returns the exit code (0).
  int run();

  // What run() wires to the channels, and its 10 ms timer (polls the refit, publishes, reports):
  // public so that a test drives the service without a network.
  void on_sensor_block(const sensor_block_t& msg) noexcept;
  void on_params(const mem_params_t& msg);
  void on_control(const control_t& msg);
  void on_tick(std::int64_t now_us);

  const std::string& process() const noexcept { return process_; }
  ReidentCore& core() noexcept { return *core_; }

 private:
  void log_wrong_axes(std::int8_t n_axes, std::int64_t now_ns) noexcept;  // rate-limited
  void publish_decision(const RefitDecision& d);
  void publish_model(const ModelDecision& d);
  void pin_model(const control_t& msg);
  CounterSet::Entries counter_entries();  // the core's counters by name, cumulative
  void publish_status(std::int64_t now_us, bool stopping);

  lcm::LCM& lcm_;
  ReidentOptions options_;
  std::string process_;  // process_name(options_.axis)
  std::string own_source_;
  std::unique_ptr<ReidentCore> core_;
  Publisher<mem_params_t> params_out_;
  std::unique_ptr<ModelChooser> chooser_;
  Publisher<model_params_t> model_out_;
  model_params_t model_msg_{};
  StatusReporter status_;
  ControlFilter control_filter_;
  ControlAcks acks_;  // what was done with the last requests, for their senders
  // Log lines triggered by messages: at most one a second per kind (the next says how many were not).
  enum LogReason : std::size_t { kLogAdopted, kLogStale, kLogInvalid, kLogReset, kLogWrongAxes, kLogOtherAxis };
  LogLimiter log_limiter_;
  LatencyStats block_cost_;  // HX_SENSOR handler (feed of one block) cost [ns], per status period
  // RESET_COUNTERS: the endpoints' counts at the reset (they only count up).
  CounterSet reported_;  // RESET_COUNTERS baselines of the counters and endpoints
  mem_params_t out_{};
  std::int64_t next_status_us_ = 0;
  bool forged_logged_ = false;             // a set with our id we never published: warned once
  std::int64_t forged_seen_us_ = 0;        // steady time of the last one [us]
  std::uint64_t wrong_axes_reported_ = 0;  // sensor_blocks_wrong_axes at the last status report
  // Last: their handlers use everything above.
  std::unique_ptr<Subscription<sensor_block_t>> sensor_;
  std::unique_ptr<Subscription<command_block_t>> command_;
  std::unique_ptr<Subscription<mem_params_t>> params_in_;
  std::unique_ptr<Subscription<control_t>> control_;
  // New references (requests; sent more than once, each version restarts the window once).
  std::unique_ptr<Subscription<trajectory_t>> trajectory_;
  std::unique_ptr<Subscription<scan_t>> scan_;
  std::int64_t trajectory_version_ = -1;
  // The last trajectory requested for our axis: a request for the same line (shape, amplitude,
  // frequency, offset) is no new reference, and the first one heard has nothing to differ from.
  std::optional<std::array<double, 4>> last_line_;
  std::int64_t scan_version_ = -1;
  std::unique_ptr<RigCheck> rig_check_;  // refuses this process when the bridge's actuator range is not its own
};

}  // namespace hystloop
