#pragma once
// hystloop-compensator: one I/O thread, and one that checks trajectories (TrajectoryChecker: a
// dry run can outlast the horizon the bridge holds). Each HX_SENSOR block is observed tick by tick and
// answered in its handler with HX_COMMAND blocks for every tick not yet planned up to the
// horizon ahead (Compensator::plan); HX_TRAJECTORY, HX_PARAMS and HX_CONTROL change the
// reference, the MEM parameters, the mode and the experiments. The commands are a
// deterministic function of the messages received, in order: no wall clock reaches the
// control law (a sample's utime only maps a trajectory's start time to loop time).
//
// nothing lost, nothing unsafe:
// - A sensor block far from the stream (further than the horizon from the next expected tick,
//   ahead or behind) is held until SequenceGuard::kConfirmBlocks consecutive blocks confirm the
//   new numbering (a bridge restart restarts the control law; a jump is followed); one forged or
//   corrupted block is ignored and the real blocks around it answered. Counted on HX_STATUS:
//   bridge_restarts, sensor_jumps, sensor_jumps_ignored, sensor_blocks_held; logged in report().
// - HX_PARAMS versions are ordered per publisher (ParamsAdmission): a set is stale only against
//   the last one accepted from the same mem_params_t.publisher_id. Refusals are counted by reason
//   (params_invalid, params_stale = params_stale_repeat + params_stale_below, params_rejected) and
//   logged once per reason and publisher. A publisher frozen out (its sets refused as stale below
//   the version accepted from it, e.g. after a forged set with its id and a huge version:
//   ParamsAdmission::frozen) makes HX_STATUS DEGRADED, naming it and both versions.
// - HX_MODEL (model_params_t) carries any model: admitted as HX_PARAMS is (one version
//   order per publisher over both channels), then Compensator::offer_model switches the
//   feedforward at the next reversal; a kind or format this build does not know is counted
//   (model_unknown_kind, model_unknown_format). model_switches and reanchors count the swaps.
// - Lines triggered by messages are rate-limited (LogLimiter, one per reason a second) and text
//   off the wire is escaped (escape_wire). HX_STATUS goes out once a second, and at once after a
//   verdict its sender waits for, but then at most every StatusReporter::kMinImmediateInterval_ns
//   (100 ms): verdicts within it are answered by the one report that follows it.
//
// One file per concern: compensator_service.cpp (the sensor path, the plan, a restarted bridge,
// run), compensator_references.cpp (trajectories and scans), compensator_params.cpp (parameter
// sets), compensator_control.cpp (HX_CONTROL), compensator_report.cpp (HX_STATUS).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "compensator/compensator_settings.hpp"
#include "compensator/trajectory_checker.hpp"
#include "core/latency_stats.hpp"
#include <array>

#include "core/log_limiter.hpp"
#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/model_params_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/scan_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "lcm/channels.hpp"
#include "lcm/control_filter.hpp"
#include "lcm/publisher.hpp"
#include "lcm/subscription.hpp"
#include "loop/compensator.hpp"
#include "loop/params_admission.hpp"
#include "loop/sequence_discontinuities.hpp"
#include "loop/sequence_guard.hpp"
#include "runtime/control_acks.hpp"
#include "runtime/counter_set.hpp"
#include "runtime/rig_check.hpp"
#include "runtime/status_reporter.hpp"

namespace hystloop {

// The compensator's own counters (cumulative; RESET_COUNTERS reports them from a baseline).
struct CompensatorServiceCounters {
  std::uint64_t command_blocks_published = 0;
  // Sensor blocks of another number of axes than this compensator's: not used, never
  // assigned to an axis by guess.
  std::uint64_t sensor_blocks_wrong_axes = 0;
  std::uint64_t command_ticks_published = 0;
  std::uint64_t params_invalid = 0;        // valid = false: diagnostic sets, never used
  std::uint64_t params_stale = 0;          // version not above the last one accepted from the same publisher
  std::uint64_t params_stale_repeat = 0;   // ... the very version accepted (a repeat): harmless
  std::uint64_t params_stale_below = 0;    // ... below it: the publisher may be frozen out
  std::uint64_t params_refused = 0;        // failed the compensator's own validation
  std::uint64_t model_unknown_kind = 0;    // HX_MODEL: a kind this build does not know
  std::uint64_t model_unknown_format = 0;  // HX_MODEL: another format_version
  std::uint64_t trajectories = 0;          // applied
  std::uint64_t trajectory_repeats = 0;    // same version again (UDP repeats)
  std::uint64_t trajectory_refused = 0;
  std::uint64_t trajectory_late_start = 0;  // start time already past: started now instead
  std::uint64_t control_acted = 0;
  std::uint64_t control_refused = 0;
  std::uint64_t bridge_restarts = 0;  // sample seq went back (confirmed): the control law was restarted
  std::uint64_t plan_mismatch = 0;    // the axes' laws planned different ticks: nothing published (a bug)
  std::uint64_t scans = 0;            // scans taken (configured or HX_SCAN)
  std::uint64_t scans_refused = 0;
  std::uint64_t wrong_axis = 0;  // a trajectory, parameter set or experiment for an axis the stage lacks
  // The last trajectory_t.version taken (as given or shaped), refused, shaped: what
  // hystloop-ctl trajectory waits for.
  std::int64_t trajectory_version = 0;
  std::int64_t trajectory_refused_version = 0;
  std::int64_t trajectory_shaped_version = 0;
  // On HX_STATUS besides: the SequenceGuard's sensor_blocks_held (not used while a jump or a
  // restart was unconfirmed), sensor_jumps_ignored (never confirmed: a forged or corrupted
  // block) and sensor_jumps (confirmed jumps ahead).
};

class CompensatorService {
 public:
  CompensatorService(const CompensatorSettings& settings, lcm::LCM& lcm, const ChannelNames& channels);

  // Runs until SIGINT/SIGTERM, SHUTDOWN or compensator.run_seconds. Returns 0, or 1 on LCM errors.
  int run();
  // At exit, run() writes the run's figures (as its summary log lines) to this JSON file.
  void write_summary_to(std::string path) { summary_json_path_ = std::move(path); }
  // Writes it now: every HX_STATUS counter under its name, over the whole run (compensator_summary.cpp).
  void write_summary_json() const;

  // The handlers, public so that tests can drive the service without a network.
  void on_sensor(const sensor_block_t& msg, std::int64_t recv_utime) noexcept;
  // HX_TRAJECTORY: checked off this thread (TrajectoryChecker), taken or refused when the check
  // ends (at the next sensor block or I/O period after it).
  void on_trajectory(const trajectory_t& msg);
  // For tests: waits for every trajectory being checked and takes (or refuses) it.
  void settle_trajectories();
  // HX_SCAN: a path of every axis (its verdict reported as a trajectory's, under its version).
  void on_scan(const scan_t& msg);
  void on_params(const mem_params_t& msg);
  // HX_MODEL: any model; the feedforward switches to it at the next reversal (compensator_params.cpp).
  void on_model(const model_params_t& msg);
  void on_control(const control_t& msg);
  // HX_STATUS; end_period false: an extra report between the periodic ones (a trajectory's
  // verdict), which leaves the period's timing and sample counts running.
  void report(std::int64_t utime, bool stopping, bool end_period = true);
  // The extra report a verdict asked for, if one is due and StatusReporter's interval allows it
  // now; else it stays due (the I/O loop sends it when the interval has passed). True if sent.
  bool report_if_due() noexcept;
  // HX_STATUS reports published so far.
  std::uint64_t reports_published() const noexcept { return status_.published(); }

  const Compensator& compensator() const noexcept { return *laws_[0]; }  // x's
  const Compensator& compensator(int axis) const noexcept { return *laws_[static_cast<std::size_t>(axis)]; }
  int axes() const noexcept { return settings_.axes; }
  const CompensatorServiceCounters& counters() const noexcept { return counters_; }
  const SequenceGuard::Counters& sequence_counters() const noexcept { return guard_.counters(); }

 private:
  // Checks `spec` on the checker's thread (check_elsewhere), or here and at once (the first
  // sample's: no command of ours is buffered yet), and takes it; throws ParameterError when refused here.
  void apply_trajectory(TrajectorySpec spec, std::int64_t start_utime, std::int64_t version, int axis,
                        bool check_elsewhere = true);
  // The axis a message names, when this stage has it; else throws ParameterError naming `field`.
  Compensator& law(int axis, const char* field);
  void decide_trajectory(std::int64_t version, const std::string& verdict, bool refused, bool shaped);
  void refuse_trajectory(std::int64_t version, const std::string& why);  // counted, logged, reported
  void taken(const TrajectoryVerdict& v, std::int64_t version, const TrajectorySpec& requested);  // the same
  // Commits (or refuses) the trajectories whose check has ended. On the I/O thread.
  void take_checked_trajectories();
  // What HX_PARAMS and HX_MODEL sets share: admit() refuses a diagnostic or stale set (counted,
  // logged once per reason and publisher); offer() validates and offers an admitted one.
  struct ParamsHeader {
    std::string_view what;  // "MEM", "pi", ... for the log
    std::int32_t version;
    std::int64_t publisher_id;
    bool valid;
    std::string_view source;
    double residual_m;
    int axis;  // the axis whose actuator it models
  };
  bool admit(const ParamsHeader& header);
  void offer(const ParamsHeader& header, const ModelParamSet& set, bool switch_model);
  void publish_plan() noexcept;
  void restart_control_law();
  void log_sequence_events();
  // Log-line reasons (LogLimiter): each at most once a second, the next saying how many were suppressed.
  enum LogReason : std::size_t {
    kLogTrajectory,
    kLogTrajectoryRefused,
    kLogParamsAccepted,
    kLogControl,
    kLogControlRefused,
    kLogParamsInvalid,
    kLogParamsStale,
    kLogParamsRefused,
    kLogModelUnknown,
    kLogSensorRestart,
    kLogSensorJump,
    kLogSensorIgnored
  };
  CounterSet::Entries collect_counters() const;

  CompensatorSettings settings_;
  lcm::LCM& lcm_;
  // One control law per axis (laws_[0]: x; the stage status and the experiment's mode report x's).
  std::array<std::optional<Compensator>, kMaxAxes> laws_;
  Compensator& x() noexcept { return *laws_[0]; }
  const Compensator& x() const noexcept { return *laws_[0]; }
  template <class Fn>
  void for_each_law(Fn&& fn) {
    for (int a = 0; a < settings_.axes; ++a) fn(*laws_[static_cast<std::size_t>(a)]);
  }
  // The configured scan, taken by every axis with the first sample (refused: logged, counted).
  void take_configured_scan();
  // `scan` on every axis, its path starting at loop time start_s; every axis checks its share first
  // (a copy of its law), then all take it or none does (throws ParameterError: why). Returns the note
  // of the verdict.
  std::string take_scan(const ScanSettings& scan, double start_s);
  // A scan's path has not ended on some axis (its plan has not reached the path's end).
  bool scan_running() const noexcept;
  Publisher<command_block_t> command_pub_;
  command_block_t command_{};                                                         // storage reserved
  std::array<std::array<CommandTick, command_block_t::MAX_TICKS>, kMaxAxes> plan_{};  // per axis
  Subscription<sensor_block_t> samples_;
  Subscription<trajectory_t> trajectories_;
  Subscription<scan_t> scans_;
  Subscription<mem_params_t> params_;
  Subscription<model_params_t> models_;
  Subscription<control_t> control_;
  RigCheck rig_check_;  // refuses this process when the bridge's actuator limits are not its own
  ControlFilter filter_{"compensator"};
  ControlAcks acks_;  // what was done with the last requests, for their senders
  StatusReporter status_;

  // What maps utime to loop time, and a trajectory whose start time needs it.
  bool have_sample_ = false;
  bool scan_taken_ = false;
  std::array<std::string, kMaxAxes>
      axis_params_counter_;  // "y_params_version", ...  // the configured scan is taken once, with the first sample
  std::int64_t last_sample_utime_ = 0;
  std::optional<TrajectorySpec> pending_trajectory_;  // a timed start that arrived before the first sample
  std::int64_t pending_start_utime_ = 0;
  std::int64_t trajectory_version_ = 0;
  std::int64_t pending_version_ = 0;   // of pending_trajectory_
  int pending_axis_ = 0;               // of pending_trajectory_
  std::int64_t refused_version_ = 0;   // the last trajectory_t.version refused
  std::int64_t checking_version_ = 0;  // the last trajectory_t.version sent to the checker
  // The laws' generation: a bridge restart replaces them, and a check of the old ones is void.
  std::uint64_t law_epoch_ = 0;
  TrajectoryChecker checker_;  // declared late: its thread ends before the members it never touches
  // The last verdict on a trajectory, in HX_STATUS's detail for a while after it was decided.
  std::string verdict_;
  std::int64_t verdict_until_ns_ = 0;
  bool verdict_due_ = false;
  std::uint64_t clamped_reported_ = 0, slew_clamped_reported_ = 0;  // u_clamped, u_slew_clamped at the last report
  std::uint64_t clamped_in_period_ = 0;
  ParamsAdmission admission_;  // the last version accepted, per publisher
  SequenceGuard guard_;        // sensor seq: a jump or a restart is believed once confirmed
  std::uint64_t restarts_logged_ = 0;
  std::uint64_t jumps_logged_ = 0;
  std::uint64_t ignored_logged_ = 0;
  SequenceDiscontinuities discontinuities_;  // where the last confirmed jump and restart went
  LogLimiter log_limiter_;

  CompensatorServiceCounters counters_;
  CompensatorCounters retired_{};  // counted by control laws a bridge restart replaced
  LatencyStats latency_;           // sensor block received (LCM's receive time) -> its answer published [ns]
  LatencyStats work_;              // handler work per sensor block [ns]
  LatencyStats latency_total_;
  std::uint64_t blocks_in_period_ = 0;
  std::uint64_t swaps_reported_ = 0;
  CounterSet reported_;
  std::string summary_json_path_;
};

}  // namespace hystloop
