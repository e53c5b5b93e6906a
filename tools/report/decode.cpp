#include "decode.hpp"

#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/model_params_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/trajectory_t.hpp"

namespace hystloop::report {

MessageKind message_kind(const lcm::LogEvent& event) noexcept {
  if (has_fingerprint_of<sensor_block_t>(event)) return MessageKind::kSensor;
  if (has_fingerprint_of<command_block_t>(event)) return MessageKind::kCommand;
  if (has_fingerprint_of<trajectory_t>(event)) return MessageKind::kTrajectory;
  if (has_fingerprint_of<mem_params_t>(event)) return MessageKind::kParams;
  if (has_fingerprint_of<model_params_t>(event)) return MessageKind::kModel;
  if (has_fingerprint_of<service_status_t>(event)) return MessageKind::kStatus;
  if (has_fingerprint_of<control_t>(event)) return MessageKind::kControl;
  return MessageKind::kUnknown;
}

const char* lcm_type_name(MessageKind kind) noexcept {
  switch (kind) {
    case MessageKind::kSensor: return "hystloop.sensor_block_t";
    case MessageKind::kCommand: return "hystloop.command_block_t";
    case MessageKind::kTrajectory: return "hystloop.trajectory_t";
    case MessageKind::kParams: return "hystloop.mem_params_t";
    case MessageKind::kModel: return "hystloop.model_params_t";
    case MessageKind::kStatus: return "hystloop.service_status_t";
    case MessageKind::kControl: return "hystloop.control_t";
    case MessageKind::kUnknown: break;
  }
  return "unknown";
}

}  // namespace hystloop::report
