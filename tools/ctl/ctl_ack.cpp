#include "ctl_ack.hpp"

#include <algorithm>
#include <utility>

#include "ctl_health.hpp"

namespace hystloop::ctl {

namespace {

// The reason a process gives: "request <id> refused: <why>" in its detail, up to the next "; ".
std::string refusal_reason(const std::string& detail, std::int64_t id) {
  const std::string prefix = "request " + std::to_string(id) + " refused: ";
  const auto at = detail.find(prefix);
  if (at == std::string::npos) return detail.empty() ? "(no reason given; see its log)" : detail;
  return detail.substr(at + prefix.size());
}

}  // namespace

AckReading read_ack(const service_status_t& status, std::int64_t id, const StateCheck& state) {
  AckReading r;
  const auto acted = find_counter(status, "control_acted_request");
  const auto refused = find_counter(status, "control_refused_request");
  r.acknowledges = acted.has_value();
  r.detail = status.detail;
  if (refused == id) {
    r.outcome = AckOutcome::kRefused;
    r.detail = refusal_reason(status.detail, id);
  } else if (acted == id) {
    r.outcome = !state || state(status) ? AckOutcome::kConfirmed : AckOutcome::kActed;
  } else if (acted.value_or(0) > id || refused.value_or(0) > id) {
    r.outcome = AckOutcome::kSkipped;
  }
  return r;
}

StateCheck counter_is(std::string name, std::int64_t value) {
  return [name = std::move(name), value](const service_status_t& s) { return find_counter(s, name) == value; };
}

AckTracker::AckTracker(std::int64_t request_id, std::vector<std::string> expected, StateCheck state)
    : id_(request_id), expected_(std::move(expected)), state_(std::move(state)) {}

void AckTracker::update(const service_status_t& status) {
  if (!expected_.empty() && std::find(expected_.begin(), expected_.end(), status.process) == expected_.end()) return;
  Answer& a = heard_[status.process];
  const AckReading r = read_ack(status, id_, state_);
  a.heard = true;
  a.last = status;
  // Once answered, an answer stays: a later report (of a later request) does not take it back;
  // an acted request still waits for its state.
  if (a.reading.outcome == AckOutcome::kPending || a.reading.outcome == AckOutcome::kActed) {
    if (r.outcome == AckOutcome::kSkipped && a.reading.outcome == AckOutcome::kActed) {
      // acted on ours, then another: the state check decides (a later request may have undone it)
      a.reading.outcome = !state_ || state_(status) ? AckOutcome::kConfirmed : AckOutcome::kActed;
    } else if (r.outcome != AckOutcome::kPending || a.reading.outcome == AckOutcome::kPending) {
      a.reading = r;
    } else if (a.reading.outcome == AckOutcome::kActed && state_ && state_(status)) {
      a.reading.outcome = AckOutcome::kConfirmed;
    }
  }
  a.reading.acknowledges = a.reading.acknowledges || r.acknowledges;
}

std::map<std::string, AckTracker::Answer> AckTracker::answers() const {
  std::map<std::string, Answer> out;
  for (const std::string& p : expected_) out[p];
  for (const auto& [name, answer] : heard_) out[name] = answer;
  return out;
}

bool AckTracker::all_confirmed(bool gathering_over) const {
  if (expected_.empty() && (!gathering_over || heard_.empty())) return false;
  for (const auto& [name, a] : answers()) {
    if (a.reading.outcome != AckOutcome::kConfirmed) return false;
  }
  return true;
}

bool AckTracker::finished(bool gathering_over) const {
  for (const auto& [name, a] : heard_) {
    if (a.reading.outcome == AckOutcome::kRefused || a.reading.outcome == AckOutcome::kSkipped) return true;
  }
  return all_confirmed(gathering_over);
}

std::vector<std::string> describe_answers(const AckTracker& tracker, bool gathering_over) {
  std::vector<std::string> lines;
  for (const auto& [name, a] : tracker.answers()) {
    std::string line = "'" + name + "' ";
    if (!a.heard) {
      line += "sent no status report (is it running, under this name?)";
    } else {
      switch (a.reading.outcome) {
        case AckOutcome::kConfirmed: line += "confirmed"; break;
        case AckOutcome::kRefused: line += "refused it: " + a.reading.detail; break;
        case AckOutcome::kSkipped:
          line += "answered a later request before reporting this one (another sender?): not confirmed";
          break;
        case AckOutcome::kActed:
          line += "took it, but its report does not show the change yet: " + state_name(a.last.state) +
                  (a.last.detail.empty() ? "" : " (" + a.last.detail + ")");
          break;
        case AckOutcome::kPending:
          line += !a.reading.acknowledges
                      ? "did not confirm: its reports carry no control_acted_request (a build that does not answer?)"
                      : "did not confirm (last report: " + state_name(a.last.state) +
                            (a.last.detail.empty() ? "" : ", " + a.last.detail) + ")";
          break;
      }
    }
    lines.push_back(std::move(line));
  }
  if (lines.empty() && gathering_over) lines.emplace_back("no process reported on the status channel");
  return lines;
}

}  // namespace hystloop::ctl
