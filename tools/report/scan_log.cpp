#include "scan_log.hpp"

#include <set>
#include <string>
#include <string_view>
#include <utility>

#include "decode.hpp"
#include "lcm/status_counters.hpp"
#include "lcm/trajectory_shape.hpp"
#include "log_reader.hpp"

namespace hystloop::report {

namespace {

std::string_view shape_name(std::int8_t shape) noexcept {
  const auto known = trajectory_shape_from_wire(shape);
  return known ? to_string(*known) : "unknown";
}

std::optional<ScanControl::Kind> control_kind(const control_t& c) noexcept {
  switch (c.command) {
    case control_t::SET_LEARNING:
      if (c.learning == control_t::LEARNING_OFF) return ScanControl::Kind::kLearningOff;
      if (c.learning == control_t::LEARNING_ON) return ScanControl::Kind::kLearningOn;
      if (c.learning == control_t::LEARNING_RESET) return ScanControl::Kind::kLearningReset;
      return std::nullopt;
    case control_t::SET_MODE:
      // The re-identifier's pin-model request is a SET_MODE too; it changes the feedforward only
      // through HX_MODEL, which is no boundary (any axis's re-identifier: reidentifier, reidentifier-y, ...).
      if (c.target.rfind("reidentifier", 0) == 0) return std::nullopt;
      return ScanControl::Kind::kMode;
    case control_t::START_EXPERIMENT: return ScanControl::Kind::kExperiment;
    case control_t::DISARM:
    case control_t::SHUTDOWN: return ScanControl::Kind::kStop;
    default: return std::nullopt;
  }
}

}  // namespace

bool ScanTrajectory::periodic() const noexcept {
  return (shape == "sine" || shape == "cosine" || shape == "triangle") && frequency_hz > 0.0;
}

ScanEvents read_scan_events(const std::vector<std::filesystem::path>& files, const ChannelNames& channels,
                            const std::string& compensator_process, int axis) {
  ScanEvents out;
  std::set<std::int64_t> versions, requests;
  trajectory_t trajectory;
  control_t control;
  service_status_t status;
  for_each_event(files, [&](const lcm::LogEvent& event) {
    const std::int64_t t = event.timestamp;
    if (event.channel == channels.trajectory) {
      if (!decode_checked(event, trajectory) || trajectory.axis != axis ||
          !versions.insert(trajectory.version).second) {
        return;
      }
      out.trajectories.push_back({t, trajectory.version, std::string(shape_name(trajectory.shape)),
                                  trajectory.amplitude_m, trajectory.offset_m, trajectory.frequency_Hz,
                                  trajectory.blend_s, trajectory.corner_s,
                                  trajectory.if_infeasible == trajectory_t::SHAPE});
    } else if (event.channel == channels.control) {
      if (!decode_checked(event, control)) return;
      const auto kind = control_kind(control);
      // Whoever a request names: a scenario addresses them to the process that acts on them (or
      // to every process), and a segment boundary too many only splits a segment.
      if (!kind || !requests.insert(control.request_id).second) return;
      out.controls.push_back({t, *kind});
    } else if (event.channel == channels.status) {
      if (!decode_checked(event, status) || status.process != compensator_process) return;
      ScanCompensatorStatus s;
      s.recv_utime = t;
      s.detail = status.detail;
      s.trajectory_version = find_counter(status, "trajectory_version");
      s.trajectory_refused_version = find_counter(status, "trajectory_refused_version");
      s.trajectory_shaped_version = find_counter(status, "trajectory_shaped_version");
      if (axis == 0) {  // x's learner (above)
        s.learning_active = find_counter(status, "learning_active");
        s.learning_periods = find_counter(status, "learning_periods");
        s.learning_rms_pm = find_counter(status, "learning_rms_pm");
      }
      s.model_switches = find_counter(status, "model_switches");
      s.params_swapped = find_counter(status, "params_swapped");
      out.compensator.push_back(std::move(s));
    }
  });
  return out;
}

std::string compensator_mode(const std::string& detail) {
  static const std::string key = "mode ";
  std::size_t at = 0;
  while ((at = detail.find(key, at)) != std::string::npos) {
    // "mode" as a word: at the start or after a separator (not e.g. "...model ").
    if (at == 0 || detail[at - 1] == ' ' || detail[at - 1] == ';') {
      const std::size_t from = at + key.size();
      const std::size_t end = detail.find_first_of(", ;", from);
      return detail.substr(from, end == std::string::npos ? std::string::npos : end - from);
    }
    at += key.size();
  }
  return "";
}

std::string verdict_text(const std::string& detail, std::int64_t version, const std::string& what) {
  const std::string prefix = "trajectory " + std::to_string(version) + " " + what + ": ";
  const std::size_t at = detail.find(prefix);
  if (at == std::string::npos) return "";
  const std::size_t from = at + prefix.size();
  // The detail joins its parts with "; ", and a reason may hold "; " too: it ends where one of
  // the parts the compensator adds after its verdict begins.
  static const char* const kNextParts[] = {"learning ", "stage ", "mode ", "feedforward clamped", "trajectory "};
  std::size_t end = std::string::npos;
  for (std::size_t at_sep = detail.find("; ", from); at_sep != std::string::npos;
       at_sep = detail.find("; ", at_sep + 2)) {
    for (const char* part : kNextParts) {
      if (detail.compare(at_sep + 2, std::char_traits<char>::length(part), part) == 0) end = at_sep;
    }
    if (end != std::string::npos) break;
  }
  return detail.substr(from, end == std::string::npos ? std::string::npos : end - from);
}

}  // namespace hystloop::report
