#include "code_legend.hpp"

#include <algorithm>
#include <string>
#include <utility>

#include "core/edit_distance.hpp"
#include "hystloop/command_block_t.hpp"
#include "hystloop/control_t.hpp"
#include "hystloop/model_params_t.hpp"
#include "hystloop/scan_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/service_status_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "models/model_set.hpp"

namespace hystloop::report {

namespace {

// "MODE_LINEAR" without "MODE_", in lower case: "linear".
Code code(std::int64_t value, std::string_view constant, std::string_view prefix) {
  if (constant.substr(0, prefix.size()) == prefix) constant.remove_prefix(prefix.size());
  return {value, ascii_lower(constant)};
}

// HX_CODES(type, prefix, A, B, ...): code(type::A, "A", prefix), code(type::B, "B", prefix), ...:
// each value from the generated constant, its name from the constant's own spelling, the type and
// prefix written once for a field. A recursion through __VA_OPT__, one constant per rescan of
// HX_EXPAND: up to 41 constants (a longer list fails to compile, naming HX_CODES_AGAIN).
#define HX_EXPAND(...) HX_EXPAND3(HX_EXPAND3(HX_EXPAND3(__VA_ARGS__)))
#define HX_EXPAND3(...) HX_EXPAND2(HX_EXPAND2(HX_EXPAND2(__VA_ARGS__)))
#define HX_EXPAND2(...) HX_EXPAND1(HX_EXPAND1(HX_EXPAND1(__VA_ARGS__)))
#define HX_EXPAND1(...) __VA_ARGS__
#define HX_CODES(type, prefix, ...) HX_EXPAND(HX_CODES_FROM(type, prefix, __VA_ARGS__))
#define HX_CODES_FROM(type, prefix, constant, ...) \
  code(type::constant, #constant, prefix) __VA_OPT__(, HX_CODES_AGAIN HX_PARENS(type, prefix, __VA_ARGS__))
#define HX_CODES_AGAIN() HX_CODES_FROM
#define HX_PARENS ()

// The online models' numbers and names are the registry's (models/model_set.hpp), whether or not
// the .lcm names them too; in the order of their numbers.
std::vector<Code> by_value(std::vector<Code> codes) {
  std::sort(codes.begin(), codes.end(), [](const Code& a, const Code& b) { return a.value < b.value; });
  return codes;
}

std::vector<Code> modes() {
  std::vector<Code> codes{HX_CODES(command_block_t, "MODE_", MODE_OFF, MODE_EXPERIMENT)};
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
  return {HX_CODES(model_params_t, "SHAPING_", SHAPING_LINEAR, SHAPING_POLYNOMIAL, SHAPING_TANH)};
}

std::vector<CodeLegend> make_legends() {
  constexpr std::string_view sensor = "hystloop.sensor_block_t";
  constexpr std::string_view command = "hystloop.command_block_t";
  constexpr std::string_view control = "hystloop.control_t";
  constexpr std::string_view trajectory = "hystloop.trajectory_t";
  constexpr std::string_view status = "hystloop.service_status_t";
  constexpr std::string_view model = "hystloop.model_params_t";
  constexpr std::string_view scan = "hystloop.scan_t";
  return {
      {sensor,
       "flags",
       {HX_CODES(sensor_block_t, "", SATURATED, SAFE_STATE, SIMULATED, SLEW_LIMITED, LATE_COMMAND, SENSOR_FAULT)},
       true},
      {command, "mode", modes()},
      {control,
       "command",
       {HX_CODES(control_t, "", SET_MODE, SET_GAINS, ARM, DISARM, START_EXPERIMENT, STOP_EXPERIMENT, RESET_COUNTERS,
                 SHUTDOWN, SET_LEARNING, HOLD_PARAMS, RELEASE_PARAMS)}},
      {control, "mode", modes()},
      {control, "learning", {HX_CODES(control_t, "LEARNING_", LEARNING_OFF, LEARNING_ON, LEARNING_RESET)}},
      {control, "axis", {HX_CODES(control_t, "", EVERY_AXIS)}},  // else the axis's number: 0 x, 1 y, 2 z
      {trajectory, "shape", {HX_CODES(trajectory_t, "", HOLD, SINE, COSINE, TRIANGLE, POINTS)}},
      {trajectory, "if_infeasible", {HX_CODES(trajectory_t, "", REFUSE, SHAPE)}},
      {status, "state", {HX_CODES(service_status_t, "", STARTING, HEALTHY, DEGRADED, SAFE, STOPPING)}},
      {model, "kind", model_kinds()},
      {model, "stage_kind", {HX_CODES(model_params_t, "STAGE_", STAGE_UNCHANGED, STAGE_NONE, STAGE_SECOND_ORDER)}},
      {model,
       "stage_order",
       {HX_CODES(model_params_t, "ORDER_", ORDER_HYSTERESIS_THEN_STAGE, ORDER_STAGE_THEN_HYSTERESIS)}},
      {model, "kat_in_shaping", shapings()},
      {model, "kat_out_shaping", shapings()},
      {scan, "path", {HX_CODES(scan_t, "", RASTER, LISSAJOUS)}},
      {scan, "slow_mode", {HX_CODES(scan_t, "", STEPS, RAMP)}},
  };
}

#undef HX_EXPAND
#undef HX_EXPAND3
#undef HX_EXPAND2
#undef HX_EXPAND1
#undef HX_CODES
#undef HX_CODES_FROM
#undef HX_CODES_AGAIN
#undef HX_PARENS

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
