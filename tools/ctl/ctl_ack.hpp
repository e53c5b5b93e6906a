#pragma once
// Whether the processes a control request was for have answered it, from their HX_STATUS reports.
// No I/O here: the caller feeds the reports in (ctl_link.cpp's send_control listens).
//
// A process that acts on a request reports its id in the counter control_acted_request, one that
// refuses it in control_refused_request (and why, in its detail), right after it answers. Where a
// request changes state that the report shows (armed, mode, held), the request is confirmed only
// when the report shows the new state too: "acted" alone may still be on its way to the real-time
// thread.

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "hystloop/service_status_t.hpp"

namespace hystloop::ctl {

enum class AckOutcome : std::int8_t {
  kPending,    // nothing about this request yet
  kActed,      // acted on, but the report does not show the new state yet
  kConfirmed,  // acted on, and the state shows it
  kRefused,    // refused (detail: why)
  kSkipped,    // a later request was answered before this one was reported (another sender?)
};

// True when a report shows the state a request asked for (e.g. armed == 1).
using StateCheck = std::function<bool(const service_status_t&)>;

struct AckReading {
  AckOutcome outcome = AckOutcome::kPending;
  std::string detail;         // kRefused: the process's reason; else its status detail
  bool acknowledges = false;  // the report carries control_acted_request (a build that answers)
};

// What one report of a process says about request `id`.
AckReading read_ack(const service_status_t& status, std::int64_t id, const StateCheck& state = {});

// A counter equal to `value`, as a StateCheck.
StateCheck counter_is(std::string name, std::int64_t value);

class AckTracker {
 public:
  // `expected`: the processes that must answer; empty = every process that reports (each one heard
  // within the gathering time must answer: HX_STATUS comes once a second from every process).
  AckTracker(std::int64_t request_id, std::vector<std::string> expected, StateCheck state = {});

  void update(const service_status_t& status);

  // Every expected process confirmed (with an empty list: at least one heard, all heard confirmed),
  // or one refused or skipped: nothing more to wait for.
  bool finished(bool gathering_over) const;
  bool all_confirmed(bool gathering_over) const;

  struct Answer {
    bool heard = false;
    AckReading reading;
    service_status_t last;  // the latest report (valid when heard)
  };
  // The expected processes (or all heard), each with what it said.
  std::map<std::string, Answer> answers() const;

 private:
  std::int64_t id_;
  std::vector<std::string> expected_;
  StateCheck state_;
  std::map<std::string, Answer> heard_;
};

// One line per process for the operator: "bridge: confirmed", "bridge: refused: <why>",
// "bridge: no status report (is it running?)", ...; and whether all confirmed.
std::vector<std::string> describe_answers(const AckTracker& tracker, bool gathering_over);

}  // namespace hystloop::ctl
