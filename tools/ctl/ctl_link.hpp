#pragma once
// hystloop-ctl's side of LCM: the connection, repeated publishing of a request, and the
// listening subcommands (status, watch, the params version look-up).

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "ctl_ack.hpp"
#include "ctl_series.hpp"
#include "ctl_verdict.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "lcm/channels.hpp"
#include "lcm/publisher.hpp"

namespace hystloop::ctl {

struct LinkOptions {
  std::string lcm_url;  // empty: $LCM_DEFAULT_URL, else the ttl=0 default
  bool allow_network = false;
  std::string rig = "HX_";
};

class CtlLink {
 public:
  // Throws ParameterError for a refused URL or prefix, std::runtime_error if LCM cannot start.
  explicit CtlLink(const LinkOptions& options);
  lcm::LCM& lcm() noexcept { return *lcm_; }
  const ChannelNames& channels() const noexcept { return channels_; }
  const std::string& url() const noexcept { return url_; }

 private:
  ChannelNames channels_;
  std::string url_;
  std::unique_ptr<lcm::LCM> lcm_;
};

using Clock = std::chrono::steady_clock;

// Dispatches what LCM holds, waiting at most `slice` and never past `deadline`; false if LCM failed.
bool receive(CtlLink& link, Clock::time_point deadline, std::chrono::microseconds slice, int max_messages = 256);
// Says so on stderr; returns 1 (the exit status).
int receive_failed(const CtlLink& link);
Clock::time_point after(double seconds);

// Publishes `msg` 3 times, 5 ms apart (UDP may drop one; receivers dedupe by request id /
// version). Returns false if the message was refused or never sent.
template <class T>
bool publish_repeated(lcm::LCM& lcm, const std::string& channel, const T& msg) {
  Publisher<T> publisher(lcm, channel);
  bool all = true;
  for (int i = 0; i < 3; ++i) {
    if (i > 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    all = publisher.publish(msg) && all;
  }
  return all;
}

struct StatusOptions {
  double listen_s = 1.5;                  // without --wait-healthy: how long to collect reports
  std::vector<std::string> wait_healthy;  // processes that must report HEALTHY
  std::vector<std::string> accept_safe;   // ... or SAFE, for these
  bool accept_degraded = false;           // ... or DEGRADED, for all
  double timeout_s = 10.0;
  bool all_counters = false;
};

// Prints one line per process; returns the exit status (0 ok, 1 nobody / not healthy in time).
int run_status(CtlLink& link, const StatusOptions& options);

struct WatchOptions {
  double seconds = 0.0;  // 0: until SIGINT/SIGTERM
  std::string bridge_process = "bridge";
  std::string compensator_process = "compensator";
  int axis = 0;  // the axis watched (0: x)
};

// Prints a line per second; returns 0 (1 if LCM failed).
int run_watch(CtlLink& link, const WatchOptions& options);

struct SeriesRunOptions {
  std::string target;            // control_t.target of the requests (empty: every process)
  double dt_s = 1e-4;            // the rig's tick [s], to follow the series from the command ticks
  bool wait = true;              // follow the series until it ends (else: send and return)
  double start_timeout_s = 3.0;  // the first experiment command must arrive within this
  int axis = 0;                  // the axis the experiments drive (0: x)
};

// Sends the steps as START_EXPERIMENT requests (the compensator queues them) and, with wait,
// prints each step as it starts. Refuses to start while an experiment runs or no commands flow.
// On SIGINT/SIGTERM it sends STOP_EXPERIMENT. Returns 0 when the series ran to its end, 1 if not.
int run_series(CtlLink& link, const std::vector<SeriesStep>& steps, const SeriesRunOptions& options);

struct VerdictOptions {
  bool wait = true;        // wait for the compensator's verdict (else: send and return)
  double timeout_s = 3.0;  // how long
  std::string compensator_process = "compensator";
};

// Publishes the trajectory (3 copies), prints "sent trajectory <description> ..." and, with wait, follows the
// compensator's HX_STATUS until it reports on msg.version (ctl_verdict.hpp), printing the verdict. Returns 0 when it
// was sent (no wait), accepted or shaped; 1 when it was refused, superseded, not confirmed within the timeout, or could
// not be published.
int publish_trajectory(CtlLink& link, const trajectory_t& msg, const std::string& description,
                       const VerdictOptions& options);

// What publishing a trajectory or a scan came to, without a word printed (a library's caller).
struct VerdictResult {
  bool published = false;
  TrajectoryVerdict verdict;  // kAccepted or kShaped when it was taken (with wait)
  std::string error;          // empty when taken (or sent without wait); else why not, in the tool's words
};
VerdictResult send_trajectory(CtlLink& link, const trajectory_t& msg, const VerdictOptions& options);
VerdictResult send_scan(CtlLink& link, const scan_t& msg, const VerdictOptions& options);
// The same for a path of every axis on HX_SCAN (the compensator reports it as a trajectory).
int publish_scan(CtlLink& link, const scan_t& msg, const std::string& description, const VerdictOptions& options);

struct AckOptions {
  bool wait = true;        // wait for the answers (else: send and return)
  double timeout_s = 3.0;  // how long
  // The processes that must answer; empty = every process heard within gather_s.
  std::vector<std::string> expected;
  StateCheck state;       // the state a confirming report shows (empty: acting is enough)
  double gather_s = 1.2;  // with no expected list: how long to collect who is running (status is 1 Hz)
};

// Publishes `msg` (3 copies) on the control channel, prints "sent <what> ...", and, with wait,
// follows the status channel until every expected process has answered (ctl_ack.hpp), printing
// each answer. `last` (if given) receives the latest report of each process heard. Returns 0 when
// sent (no wait) or confirmed by all, 1 when refused, not confirmed in time, nobody reported, or
// it could not be published.
int send_control_confirmed(CtlLink& link, const control_t& msg, const std::string& what, const AckOptions& options,
                           std::map<std::string, service_status_t>* last = nullptr);

// What a control request came to, without a word printed (send_control_confirmed prints it; a
// library's caller raises `error`).
struct ControlResult {
  bool published = false;
  bool confirmed = false;            // every expected process confirmed (or sent, without wait)
  std::vector<std::string> answers;  // one line per process: "bridge: confirmed", "bridge: refused: <why>", ...
  std::string error;                 // empty when confirmed; else why not ("no rig is running: ...")
  double waited_s = 0.0;
  std::map<std::string, service_status_t> heard;  // the latest report of each process heard
};
ControlResult request_control(CtlLink& link, const control_t& msg, const std::string& what, const AckOptions& options);

struct StatusWait {
  bool satisfied = false;
  std::map<std::string, service_status_t> last;  // the latest report of every process heard
};
// Follows the status channel until `process` sends a report that `until` accepts, or timeout_s.
StatusWait wait_for_status(CtlLink& link, const std::string& process, const StateCheck& until, double timeout_s);

// The highest parameter version seen on HX_PARAMS or in HX_COMMAND's ticks within listen_s, plus one
// (1 when nothing was seen), so that a set sent by hand supersedes the one in use.
std::int32_t next_params_version(CtlLink& link, double listen_s);

}  // namespace hystloop::ctl
