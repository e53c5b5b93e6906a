#include "runtime/stage_config.hpp"

#include <cmath>
#include <cstddef>
#include <numbers>
#include <string>

#include <spdlog/fmt/fmt.h>

#include "core/errors.hpp"
#include "runtime/config_validation.hpp"

namespace hystloop {

namespace {

std::string key(std::string_view prefix, const char* name) { return std::string(prefix) + "." + name; }

}  // namespace

LinearStageSpec read_linear_stage(const Config& config, std::string_view prefix, LinearStageSpec stage) {
  const std::string p = std::string(prefix) + ".";
  // An empty list is a form not given: the deploy file shows every form's keys, all but one empty.
  const auto given = [&](const char* key) {
    const std::string k = p + key;
    if (!config.has(k)) return false;
    if (std::string_view(key) == "modes")
      return !config.get_records(k, {"frequency_hz", "damping_ratio", "weight"}).empty();
    if (std::string_view(key) == "zeros_hz" || std::string_view(key) == "poles_hz")
      return !config.get_rows(k, 2).empty();
    if (std::string_view(key) == "discrete_dt_s") return config.get<double>(k) != 0.0;
    return !config.get<std::vector<double>>(k).empty();
  };
  std::string form;  // the first key of the form given, to name a second one
  const auto choose = [&](const char* key) {
    if (!form.empty()) config.fail(p + key, "give one form of the stage; " + p + form + " is given too");
    form = key;
  };
  const auto require_with = [&](const char* key, const char* needed) {
    if (!given(needed)) config.fail(p + needed, std::string("required with ") + p + key);
  };
  if (given("modes")) {
    choose("modes");
    const auto rows = config.get_records(p + "modes", {"frequency_hz", "damping_ratio", "weight"});
    std::vector<LinearStageSpec::Mode> modes;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const std::string entry = p + "modes[" + std::to_string(i) + "]";
      if (std::isnan(rows[i][0])) config.fail(entry + ".frequency_hz", "required");
      if (std::isnan(rows[i][1])) config.fail(entry + ".damping_ratio", "required");
      modes.push_back({rows[i][0], rows[i][1], std::isnan(rows[i][2]) ? 1.0 : rows[i][2]});
    }
    stage = LinearStageSpec::sum_of_modes(std::move(modes));
  }
  if (given("zeros_hz") || given("poles_hz")) {  // no zeros is a stage too
    choose(given("poles_hz") ? "poles_hz" : "zeros_hz");
    require_with("zeros_hz", "poles_hz");
    const auto roots = [&](const char* key) {
      std::vector<LinearStageSpec::Root> out;
      for (const auto& r : config.get_rows(p + key, 2)) out.push_back({r[0], r[1]});
      return out;
    };
    stage = LinearStageSpec::zero_pole(roots("zeros_hz"), roots("poles_hz"));
  }
  if (given("numerator_s") || given("denominator_s")) {
    choose(given("numerator_s") ? "numerator_s" : "denominator_s");
    require_with("numerator_s", "denominator_s");
    require_with("denominator_s", "numerator_s");
    stage = LinearStageSpec::transfer_function(config.get<std::vector<double>>(p + "numerator_s"),
                                               config.get<std::vector<double>>(p + "denominator_s"));
  }
  if (given("numerator_zinv") || given("denominator_zinv") || given("discrete_dt_s")) {
    choose(given("numerator_zinv")     ? "numerator_zinv"
           : given("denominator_zinv") ? "denominator_zinv"
                                       : "discrete_dt_s");
    require_with("denominator_zinv", "numerator_zinv");
    require_with("numerator_zinv", "denominator_zinv");
    require_with("numerator_zinv", "discrete_dt_s");
    stage = LinearStageSpec::discrete(config.get<std::vector<double>>(p + "numerator_zinv"),
                                      config.get<std::vector<double>>(p + "denominator_zinv"),
                                      config.get<double>(p + "discrete_dt_s"));
  }
  stage.delay_s = config.get<double>(p + "delay_s", stage.delay_s);
  return stage;
}

std::vector<std::string> linear_stage_keys(std::string_view prefix) {
  std::vector<std::string> keys;
  for (const char* name : {"modes", "poles_hz", "zeros_hz", "numerator_s", "denominator_s", "numerator_zinv",
                           "denominator_zinv", "discrete_dt_s", "delay_s"}) {
    keys.push_back(key(prefix, name));
  }
  return keys;
}

std::string describe_stage(const StageModel& stage, double dt_s) {
  if (stage.is_second_order()) {
    return fmt::format("second order k {:.6g} 1/s^2, c {:.6g} 1/s ({:.4g} Hz, zeta {:.3g}), inverted",
                       stage.second_order.k, stage.second_order.c,
                       stage.second_order.natural_frequency() / (2.0 * std::numbers::pi),
                       stage.second_order.damping_ratio());
  }
  if (!stage.is_linear()) return "none";
  try {
    const DiscreteLinearStage d = discretise(stage.linear, dt_s);
    const std::int64_t preview = stage_preview_ticks(d, stage.preview_ticks, stage.reference_bandwidth_hz);
    return fmt::format(
        "linear, order {}, lowest resonance {:.4g} Hz, delay {:.4g} s, inverted with {} ticks of preview{}",
        stage.linear.order(), stage.lowest_resonance_rad_s(1e-5) / (2.0 * std::numbers::pi), stage.linear.delay_s,
        preview,
        stage.reference_bandwidth_hz > 0.0
            ? fmt::format(" (reference low-passed at {:.4g} Hz)", stage.reference_bandwidth_hz)
            : std::string());
  } catch (const ParameterError& e) {
    return std::string("linear (not invertible: ") + e.what() + ")";
  }
}

std::vector<std::string> stage_config_keys() {
  std::vector<std::string> keys = {
      "stage.kind",       "stage.k", "stage.c", "stage.order", "stage.preview_ticks", "stage.reference_bandwidth_hz",
      "stage.known_to_hz"};
  for (std::string& k : linear_stage_keys("stage")) keys.push_back(std::move(k));
  return keys;
}

StageModel read_stage_model(const Config& config, const StageModel& defaults, double dt_s) {
  StageModel stage = defaults;
  const std::string kind = config.get<std::string>("stage.kind", "none");
  if (kind == "second_order") {
    stage.kind = StageModel::Kind::kSecondOrder;
  } else if (kind == "linear") {
    stage.kind = StageModel::Kind::kLinear;
  } else if (kind == "none") {
    stage.kind = StageModel::Kind::kNone;
    for (const char* key : {"stage.k", "stage.c"}) {
      if (config.has(key)) config.fail("stage.kind", std::string("is none: set it to second_order to use ") + key);
    }
  } else {
    config.fail("stage.kind", "must be none, second_order or linear (got '" + kind + "')");
  }
  if (stage.is_linear()) {
    for (const char* key : {"stage.k", "stage.c"}) {
      if (config.has(key)) config.fail(key, "is Banning's second order: with stage.kind linear give the stage's form");
    }
    stage.linear = read_linear_stage(config, "stage", LinearStageSpec{});
    bool given = false;
    for (const std::string& key : linear_stage_keys("stage"))
      given = given || (key != "stage.delay_s" && config.has(key));
    if (!given) {
      config.fail("stage.modes",
                  "stage.kind linear needs the stage: stage.modes, stage.poles_hz (with "
                  "stage.zeros_hz), stage.numerator_s with stage.denominator_s, or the discrete form");
    }
    stage.preview_ticks = config.get<std::int64_t>("stage.preview_ticks", 0);
    stage.reference_bandwidth_hz = config.get_non_negative("stage.reference_bandwidth_hz", 0.0);
    stage.known_to_hz = config.get_in_range("stage.known_to_hz", 0.0, 0.0, 0.5 / dt_s);
  } else {
    if (config.has("stage.known_to_hz"))
      config.fail("stage.known_to_hz", "is a linear stage's: set stage.kind to linear");
    for (const std::string& key : linear_stage_keys("stage")) {
      if (config.has(key)) config.fail(key, "is a linear stage's: set stage.kind to linear to use it");
    }
    stage.second_order.k = config.get_positive("stage.k", stage.second_order.k);
    stage.second_order.c = config.get_positive("stage.c", stage.second_order.c);
  }
  const std::string order = config.get<std::string>("stage.order", "hysteresis_then_stage");
  if (order == "hysteresis_then_stage") {
    stage.order = BanningOrder::kHysteresisThenStage;
  } else if (order == "stage_then_hysteresis") {
    stage.order = BanningOrder::kStageThenHysteresis;
  } else {
    config.fail("stage.order", "must be hysteresis_then_stage or stage_then_hysteresis (got '" + order + "')");
  }
  validate_config_section(config, "", [&] { stage.validate(dt_s); });
  return stage;
}

}  // namespace hystloop
