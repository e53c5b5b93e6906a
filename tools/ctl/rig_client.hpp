#pragma once
// A running rig from a program (the Python module's Rig): the same link, requests,
// acknowledgements and verdicts as hystloop-ctl (ctl_link.hpp), with results instead of printed
// lines and a RigError carrying the tool's reason instead of an exit status; and a recorder of
// the sensor stream (every tick of every axis, with the simulated stage's truth). Nothing here
// waits longer than the timeout it is given.

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "ctl_link.hpp"
#include "ctl_requests.hpp"
#include "hystloop/service_status_t.hpp"

namespace hystloop::ctl {

// A request not confirmed: why, in hystloop-ctl's words (each process's answer on its own line).
class RigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct RigClientOptions {
  LinkOptions link;        // LCM URL (ttl 0 unless allow_network), channel prefix
  std::string key_file;    // the rig key (auth.key_file): sign requests with it; empty: unsigned
  double timeout_s = 3.0;  // every acknowledged request waits at most this long
  std::string bridge = "bridge";
  std::string compensator = "compensator";
  void validate() const;  // ParameterError naming the field
};

// One process's latest report.
struct ProcessReport {
  std::string process;
  std::string state;  // STARTING, HEALTHY, DEGRADED, SAFE, STOPPING
  std::string detail;
  std::string host;
  std::int64_t utime = 0;  // [us since the epoch]
  std::int64_t late = 0;
  std::int64_t rejected = 0;
  std::vector<std::pair<std::string, std::int64_t>> counters;  // in the report's order
};

// Every tick of every axis over a recording, one row per tick and axis, in tick order per axis.
struct RecordedTicks {
  int axes = 0;
  double dt_s = 0.0;
  std::vector<std::int64_t> seq;  // tick number
  std::vector<std::int32_t> axis;
  std::vector<double> u_V, u_ff_V, u_fb_V, y_ref_m, y_m;
  std::vector<double> y_true_m;  // the simulated stage's true position (NaN without HX_SIM_TRUTH)
  std::vector<std::int32_t> flags;
  std::uint64_t missing_ticks = 0;  // gaps in the block sequence while recording
  std::uint64_t blocks = 0;
};

class RigClient {
 public:
  // Throws ParameterError for refused options (a URL off this host without allow_network, a bad
  // prefix or key file), std::runtime_error when LCM cannot start.
  explicit RigClient(const RigClientOptions& options);

  // The latest report of every process heard within listen_s (empty: no rig is running).
  std::vector<ProcessReport> status(double listen_s = 1.5);

  // Acknowledged requests: return when every process they are for confirmed; RigError otherwise.
  void arm();
  void disarm();
  void set_gains(const GainsRequest& gains);  // gains.axis: one axis's servo, or every axis's (-1)
  void set_mode(const std::string& mode);     // off | linear | mem | ...
  void learn(const std::string& what);        // on | off | reset
  void experiment(const ExperimentRequest& experiment, int axis = 0);
  void stop_experiment();
  // A trajectory (ctl trajectory): the compensator's verdict, "accepted[: detail]" or "shaped: detail".
  std::string set_trajectory(const TrajectoryRequest& request);
  // A MEM parameter set (ctl params): the version the compensator adopted.
  std::int32_t set_params(ParamsRequest request);

  // Every tick of the sensor stream for `seconds` (and its truth, when the stage is simulated).
  RecordedTicks record(double seconds);
  // The next sensor block's ticks (at most timeout_s of waiting; nullopt when none came).
  std::optional<RecordedTicks> next_block(double timeout_s);

  const std::string& url() const noexcept { return link_.url(); }

 private:
  void control(std::int8_t command, const std::string& target, const std::string& what,
               const std::function<void(control_t&)>& fill, const char* owner, StateCheck state = {});

  RigClientOptions options_;
  CtlLink link_;
};

}  // namespace hystloop::ctl
