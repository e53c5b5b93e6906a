#include "code_legend.hpp"

#include <algorithm>
#include <cctype>
#include <string>
#include <utility>

#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/model_params_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "models/model_set.hpp"

namespace hystloop::report {

namespace {

// "MODE_LINEAR" without "MODE_", in lower case: "linear".
Code code(std::int64_t value, std::string_view constant, std::string_view prefix) {
  if (constant.substr(0, prefix.size()) == prefix) constant.remove_prefix(prefix.size());
  std::string name(constant);
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return {value, name};
}

// The value comes from the generated constant, the name from the constant's own spelling.
#define HX_CODE(type, constant, prefix) code(type::constant, #constant, prefix)

// The online models' numbers and names are the registry's (models/model_set.hpp), whether or not
// the .lcm names them too; in the order of their numbers.
std::vector<Code> by_value(std::vector<Code> codes) {
  std::sort(codes.begin(), codes.end(), [](const Code& a, const Code& b) { return a.value < b.value; });
  return codes;
}

std::vector<Code> modes() {
  std::vector<Code> codes{HX_CODE(command_block_t, MODE_OFF, "MODE_"),
                          HX_CODE(command_block_t, MODE_EXPERIMENT, "MODE_")};
  OnlineModels::for_each([&]<class D>() { codes.push_back({D::mode, std::string(D::name)}); });
  return by_value(std::move(codes));
}

std::vector<Code> model_kinds() {
  std::vector<Code> codes;
  OnlineModels::for_each([&]<class D>() {
    codes.push_back({static_cast<std::int64_t>(D::kind), std::string(D::name)});
  });
  return by_value(std::move(codes));
}

std::vector<Code> shapings() {
  return {HX_CODE(model_params_t, SHAPING_LINEAR, "SHAPING_"), HX_CODE(model_params_t, SHAPING_POLYNOMIAL, "SHAPING_"),
          HX_CODE(model_params_t, SHAPING_TANH, "SHAPING_")};
}

std::vector<CodeLegend> make_legends() {
  constexpr std::string_view sensor = "hystloop.sensor_block_t";
  constexpr std::string_view command = "hystloop.command_block_t";
  constexpr std::string_view control = "hystloop.control_t";
  constexpr std::string_view trajectory = "hystloop.trajectory_t";
  constexpr std::string_view status = "hystloop.service_status_t";
  constexpr std::string_view model = "hystloop.model_params_t";
  return {
      {sensor,
       "flags",
       true,
       {HX_CODE(sensor_block_t, SATURATED, ""), HX_CODE(sensor_block_t, SAFE_STATE, ""),
        HX_CODE(sensor_block_t, SIMULATED, ""), HX_CODE(sensor_block_t, SLEW_LIMITED, ""),
        HX_CODE(sensor_block_t, LATE_COMMAND, ""), HX_CODE(sensor_block_t, SENSOR_FAULT, "")}},
      {command, "mode", false, modes()},
      {control,
       "command",
       false,
       {HX_CODE(control_t, SET_MODE, ""), HX_CODE(control_t, SET_GAINS, ""), HX_CODE(control_t, ARM, ""),
        HX_CODE(control_t, DISARM, ""), HX_CODE(control_t, START_EXPERIMENT, ""),
        HX_CODE(control_t, STOP_EXPERIMENT, ""), HX_CODE(control_t, RESET_COUNTERS, ""),
        HX_CODE(control_t, SHUTDOWN, ""), HX_CODE(control_t, SET_LEARNING, ""), HX_CODE(control_t, HOLD_PARAMS, ""),
        HX_CODE(control_t, RELEASE_PARAMS, "")}},
      {control, "mode", false, modes()},
      {control,
       "learning",
       false,
       {HX_CODE(control_t, LEARNING_OFF, "LEARNING_"), HX_CODE(control_t, LEARNING_ON, "LEARNING_"),
        HX_CODE(control_t, LEARNING_RESET, "LEARNING_")}},
      {trajectory,
       "shape",
       false,
       {HX_CODE(trajectory_t, HOLD, ""), HX_CODE(trajectory_t, SINE, ""), HX_CODE(trajectory_t, COSINE, ""),
        HX_CODE(trajectory_t, TRIANGLE, ""), HX_CODE(trajectory_t, POINTS, "")}},
      {trajectory, "if_infeasible", false, {HX_CODE(trajectory_t, REFUSE, ""), HX_CODE(trajectory_t, SHAPE, "")}},
      {status,
       "state",
       false,
       {HX_CODE(service_status_t, STARTING, ""), HX_CODE(service_status_t, HEALTHY, ""),
        HX_CODE(service_status_t, DEGRADED, ""), HX_CODE(service_status_t, SAFE, ""),
        HX_CODE(service_status_t, STOPPING, "")}},
      {model, "kind", false, model_kinds()},
      {model,
       "stage_kind",
       false,
       {HX_CODE(model_params_t, STAGE_UNCHANGED, "STAGE_"), HX_CODE(model_params_t, STAGE_NONE, "STAGE_"),
        HX_CODE(model_params_t, STAGE_SECOND_ORDER, "STAGE_")}},
      {model,
       "stage_order",
       false,
       {HX_CODE(model_params_t, ORDER_HYSTERESIS_THEN_STAGE, "ORDER_"),
        HX_CODE(model_params_t, ORDER_STAGE_THEN_HYSTERESIS, "ORDER_")}},
      {model, "kat_in_shaping", false, shapings()},
      {model, "kat_out_shaping", false, shapings()},
  };
}

#undef HX_CODE

}  // namespace

std::string CodeLegend::text() const {
  std::string out = bits ? "bits: " : "";
  for (const Code& c : codes) {
    if (&c != &codes.front()) out += ',';
    out += std::to_string(c.value) + '=' + c.name;
  }
  if (bits) out += " (0=none)";
  return out;
}

const std::vector<CodeLegend>& code_legends() {
  static const std::vector<CodeLegend> legends = make_legends();
  return legends;
}

const CodeLegend* find_code_legend(std::string_view type_name, std::string_view field) {
  for (const CodeLegend& legend : code_legends()) {
    if (legend.type_name == type_name && legend.field == field) return &legend;
  }
  return nullptr;
}

}  // namespace hystloop::report
