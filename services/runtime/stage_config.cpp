#include "runtime/stage_config.hpp"

#include <cstddef>
#include <numbers>
#include <string>

#include <spdlog/fmt/fmt.h>

#include "core/errors.hpp"
#include "runtime/config_validation.hpp"

namespace hystloop {

namespace {

std::string key(std::string_view prefix, const char* name) { return std::string(prefix) + "." + name; }

// A flat list read as tuples of `width` numbers: the YAML lists of the section are lists of numbers.
std::vector<double> tuples(const Config& config, const std::string& k, std::size_t width, const char* what) {
  std::vector<double> v = config.get<std::vector<double>>(k, {});
  if (v.size() % width != 0) {
    config.fail(k, "must list " + std::string(what) + " (" + std::to_string(width) + " numbers each; got " +
                       std::to_string(v.size()) + " numbers)");
  }
  return v;
}

std::vector<LinearStageSpec::Root> roots(const Config& config, const std::string& k) {
  const std::vector<double> v = tuples(config, k, 2, "[re, im] pairs in Hz");
  std::vector<LinearStageSpec::Root> out;
  for (std::size_t i = 0; i < v.size(); i += 2) out.push_back({v[i], v[i + 1]});
  return out;
}

}  // namespace

LinearStageSpec read_linear_stage(const Config& config, std::string_view prefix) {
  const std::string modes = key(prefix, "modes"), poles = key(prefix, "poles_hz"), zeros = key(prefix, "zeros_hz"),
                    num = key(prefix, "numerator_s"), den = key(prefix, "denominator_s");
  const int forms =
      int{config.has(modes)} + int{config.has(poles) || config.has(zeros)} + int{config.has(num) || config.has(den)};
  if (forms != 1) {
    config.fail(modes, "a linear stage takes exactly one form: " + modes + ", " + poles + " (with " + zeros + "), or " +
                           num + " with " + den);
  }
  const double delay_s = config.get_non_negative(key(prefix, "delay_s"), 0.0);
  if (config.has(modes)) {
    const std::vector<double> v = tuples(config, modes, 3, "modes as [frequency_Hz, damping_ratio, weight]");
    std::vector<LinearStageSpec::Mode> m;
    for (std::size_t i = 0; i < v.size(); i += 3) m.push_back({v[i], v[i + 1], v[i + 2]});
    return LinearStageSpec::sum_of_modes(std::move(m), delay_s);
  }
  if (config.has(poles) || config.has(zeros))
    return LinearStageSpec::zero_pole(roots(config, zeros), roots(config, poles), delay_s);
  return LinearStageSpec::transfer_function(config.get<std::vector<double>>(num, {}),
                                            config.get<std::vector<double>>(den, {}), delay_s);
}

std::vector<std::string> linear_stage_keys(std::string_view prefix) {
  std::vector<std::string> keys;
  for (const char* name : {"modes", "poles_hz", "zeros_hz", "numerator_s", "denominator_s", "delay_s"}) {
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
      "stage.kind", "stage.k", "stage.c", "stage.order", "stage.preview_ticks", "stage.reference_bandwidth_hz"};
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
    stage.linear = read_linear_stage(config, "stage");
    stage.preview_ticks = config.get<std::int64_t>("stage.preview_ticks", 0);
    stage.reference_bandwidth_hz = config.get_non_negative("stage.reference_bandwidth_hz", 0.0);
  } else {
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
