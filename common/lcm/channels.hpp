#pragma once
// Channel names of one rig. Every channel starts with the rig's prefix (default "HX_"),
// so two rigs on one network never mix. LCM treats a subscribed channel as a regular
// expression, so the prefix is restricted to [A-Z0-9_]: a name is then matched literally.

#include <array>
#include <string>
#include <string_view>

namespace hystloop {

inline constexpr std::string_view kDefaultRigPrefix = "HX_";

// Throws ParameterError("rig.prefix", ...) unless `prefix` is 1..32 characters of
// [A-Z0-9_], starts with a letter and ends with '_'.
void validate_rig_prefix(std::string_view prefix);

// The channels of the contract (docs/CONTRACT.md), by suffix.
inline constexpr std::string_view kSensorSuffix = "SENSOR";          // sensor_block_t, 10 kHz of ticks in blocks
inline constexpr std::string_view kCommandSuffix = "COMMAND";        // command_block_t, one block per sensor block
inline constexpr std::string_view kTrajectorySuffix = "TRAJECTORY";  // trajectory_t, on change
inline constexpr std::string_view kScanSuffix = "SCAN";              // scan_t, on change: a path of every axis
inline constexpr std::string_view kParamsSuffix = "PARAMS";          // mem_params_t, on refit
// model_params_t, on a model change: any model (HX_PARAMS stays MEM-only, so its tools and logs
// work unchanged; a channel carries one type).
inline constexpr std::string_view kModelSuffix = "MODEL";
inline constexpr std::string_view kStatusSuffix = "STATUS";    // service_status_t, 1 Hz per process
inline constexpr std::string_view kControlSuffix = "CONTROL";  // control_t, on demand
// sim_truth_t, after each sensor block, from a simulated stage only: its true position.
inline constexpr std::string_view kSimTruthSuffix = "SIM_TRUTH";

// Suffix and LCM type name ("hystloop.sensor_block_t") of every channel, e.g. for a
// logger that records them all or a tool that lists them.
struct ChannelSpec {
  std::string_view suffix;
  std::string_view type_name;
};
inline constexpr std::array<ChannelSpec, 9> kChannelSpecs{{
    {kSensorSuffix, "hystloop.sensor_block_t"},
    {kCommandSuffix, "hystloop.command_block_t"},
    {kTrajectorySuffix, "hystloop.trajectory_t"},
    {kParamsSuffix, "hystloop.mem_params_t"},
    {kStatusSuffix, "hystloop.service_status_t"},
    {kControlSuffix, "hystloop.control_t"},
    {kModelSuffix, "hystloop.model_params_t"},
    {kSimTruthSuffix, "hystloop.sim_truth_t"},
    {kScanSuffix, "hystloop.scan_t"},
}};

// The full names for one prefix, built once (publishing then never builds a string).
struct ChannelNames {
  std::string prefix;
  std::string sensor;
  std::string command;
  std::string trajectory;
  std::string params;
  std::string status;
  std::string control;
  std::string model;
  std::string sim_truth;
  std::string scan;

  // Validates the prefix (throws ParameterError naming "rig.prefix").
  explicit ChannelNames(std::string_view rig_prefix = kDefaultRigPrefix);

  // Regular expression matching every channel of this rig (and no other rig's): "HX_.*".
  std::string all_channels_regex() const { return prefix + ".*"; }
};

// One channel's full name: prefix + suffix, the prefix validated.
std::string channel_name(std::string_view rig_prefix, std::string_view suffix);

}  // namespace hystloop
