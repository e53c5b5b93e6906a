#include "runtime/stage_config.hpp"
#include "reidentifier/reident_options.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/errors.hpp"
#include "models/axis_coupling.hpp"
#include "models/model_descriptors.hpp"
#include "models/param_config.hpp"
#include "runtime/config_validation.hpp"

namespace hystloop {

namespace {
constexpr const char* kReidentKeys[] = {
    "reidentifier.axis",
    "reidentifier.rate_hz",
    "reidentifier.refit_period_s",
    "reidentifier.window_s",
    "reidentifier.capacity_s",
    "reidentifier.holdout_branches",
    "reidentifier.min_relative_improvement",
    "reidentifier.max_residual_rms_m",
    "reidentifier.max_solver_time_s",
    "reidentifier.reversal_dead_band_V",
    "reidentifier.publish_invalid",
    "reidentifier.hold",
    "reidentifier.stale_after_s",
    "reidentifier.degraded_after_poisoned",
    "reidentifier.lcm_queue",
    "reidentifier.models",
    "reidentifier.model_margin",
    "reidentifier.model_period_s",
    "reidentifier.model_regime_factor",
    "reidentifier.model_decimation",
    "reidentifier.pin_model",
    "reidentifier.plausible_gain_factor",
};

// What reidentifier.pin_model accepts: "none, mem, pi, katalenic or linear".
std::string pin_model_choices() {
  std::vector<std::string_view> names{"none"};
  const std::vector<std::string_view> models = model_kind_names();
  names.insert(names.end(), models.begin(), models.end());
  return choice_list(names);
}

// reidentifier.models, model_margin, model_period_s, model_regime_factor, model_decimation, pin_model.
void read_model_choice(const Config& config, ModelChoiceOptions& m) {
  const std::string models = config.get<std::string>("reidentifier.models", "off");
  m.enabled = models != "off";
  if (m.enabled && models != "auto") {
    std::vector<ModelKind> kinds;
    std::size_t from = 0;
    while (from <= models.size()) {
      const std::size_t comma = std::min(models.find(',', from), models.size());
      const std::string name = models.substr(from, comma - from);
      const std::optional<ModelKind> kind = parse_model_kind(name);
      if (!kind)
        config.fail("reidentifier.models", "expected off, auto or a comma-separated list of models, each " +
                                               choice_list(model_kind_names()) + " (got \"" + name + "\")");
      if (std::find(kinds.begin(), kinds.end(), *kind) != kinds.end())
        config.fail("reidentifier.models", "lists " + name + " twice");
      kinds.push_back(*kind);
      from = comma + 1;
    }
    m.selector.selection.candidates = kinds;
  }
  m.selector.margin = config.get_in_range("reidentifier.model_margin", m.selector.margin, 0.0, 0.9);
  m.period_s = config.get_in_range("reidentifier.model_period_s", m.period_s, 0.1, 3600.0);
  m.regime_factor = config.get_in_range("reidentifier.model_regime_factor", m.regime_factor, 0.0, 1e6);
  if (m.regime_factor != 0.0 && m.regime_factor < 1.0)
    config.fail("reidentifier.model_regime_factor", "must be 0 (off) or >= 1");
  m.selector.decimation =
      static_cast<std::size_t>(config.get_int_in_range("reidentifier.model_decimation", 10, 1, 1000));
  const std::string pin = config.get<std::string>("reidentifier.pin_model", "none");
  if (pin != "none") {
    m.pinned = parse_model_kind(pin);
    if (!m.pinned) config.fail("reidentifier.pin_model", "expected " + pin_model_choices() + " (got \"" + pin + "\")");
  }
  validate_config_section(config, "reident.", [&] { m.selector.validate(); });
}

// The band every set is checked against, from the keys the compensator reads too; the initial
// set must lie in it (a units error in the snippet is found at start, not at the first refit).
void read_plausibility(const Config& config, ReidentOptions& o) {
  GainPlausibility& p = o.plausibility;
  p.nominal_gain_m_per_V = config.get<double>("linear.gain", p.nominal_gain_m_per_V);
  if (!(p.nominal_gain_m_per_V > 0.0) || !std::isfinite(p.nominal_gain_m_per_V)) {
    config.fail("linear.gain",
                "must be a finite number > 0: it is the stage's nominal gain, the one every "
                "parameter set is checked against (reidentifier.plausible_gain_factor)");
  }
  p.u_min_V = config.get_in_range("actuator.u_min_V", p.u_min_V, -1e4, 1e4);
  p.u_max_V = config.get_in_range("actuator.u_max_V", p.u_max_V, -1e4, 1e4);
  if (!(p.u_max_V > p.u_min_V)) config.fail("actuator.u_max_V", "must be greater than actuator.u_min_V");
  p.factor = config.get_in_range("reidentifier.plausible_gain_factor", p.factor, GainPlausibility::kMinFactor,
                                 GainPlausibility::kMaxFactor);
  ModelParamSet initial;
  initial.mem = o.initial;
  validate_config_section(config, "", [&] { require_plausible(initial, p); });
}

// reidentifier.axis: the axis by its name, as hystloop-ctl and hystloop-identify take it (--axis).
int read_axis(const Config& config) {
  const std::string name = config.get<std::string>("reidentifier.axis", "x");
  for (int axis = 0; axis < kMaxAxes; ++axis) {
    if (name == axis_name(axis)) return axis;
  }
  config.fail("reidentifier.axis", "expected x, y or z, the stage axis this re-identifier fits (got \"" + name + "\")");
}

std::size_t samples_of(double seconds, double rate_hz) {
  return static_cast<std::size_t>(std::llround(seconds * rate_hz));
}
}  // namespace

ReidentOptions read_reident_options(const Config& config) {
  std::vector<std::string> known(std::begin(kReidentKeys), std::end(kReidentKeys));
  for (const std::string& key : config.keys()) {
    if (key.rfind("reident.", 0) == 0) {
      config.fail(key, "the section is called reidentifier: now, after the service (rename reident: to reidentifier:)");
    }
    if (key.rfind("reidentifier.", 0) != 0) known.push_back(key);
  }
  config.check_no_unknown_keys(known);

  ReidentOptions o;
  o.axis = read_axis(config);
  validate_config_section(config, "mem.",
                          [&] { o.initial = params_from_config<MemDescriptor>(config, MemParams::paper_like()); });
  read_plausibility(config, o);

  o.rate_hz = config.get_in_range("reidentifier.rate_hz", o.rate_hz, 1.0, 1e6);
  o.stage = read_stage_model(config, o.stage, 1.0 / o.rate_hz);
  o.refit_period_s = config.get_in_range("reidentifier.refit_period_s", o.refit_period_s, 0.01, 3600.0);
  o.window_s = config.get_in_range("reidentifier.window_s", o.window_s, 1e-6, 3600.0);
  o.capacity_s = config.get_in_range("reidentifier.capacity_s", o.capacity_s, 1e-6, 3600.0);
  o.publish_invalid = config.get<bool>("reidentifier.publish_invalid", o.publish_invalid);
  o.hold = config.get<bool>("reidentifier.hold", o.hold);
  o.stale_after_s = config.get_in_range("reidentifier.stale_after_s", o.stale_after_s, 0.001, 3600.0);
  o.degraded_after_poisoned =
      config.get_int_in_range("reidentifier.degraded_after_poisoned", o.degraded_after_poisoned, 1, 1000000);
  o.lcm_queue = config.get_int_in_range("reidentifier.lcm_queue", o.lcm_queue, 100, 10000000);

  OnlineMemOptions& e = o.estimator;
  e.window_samples = samples_of(o.window_s, o.rate_hz);
  if (e.window_samples < 16) {
    config.fail("reidentifier.window_s",
                "must hold at least 16 samples at reidentifier.rate_hz (got " + std::to_string(e.window_samples) + ")");
  }
  e.capacity_samples = samples_of(o.capacity_s, o.rate_hz);
  if (e.capacity_samples < e.window_samples) {
    config.fail("reidentifier.capacity_s", "must be >= reidentifier.window_s (got " + std::to_string(o.capacity_s) +
                                               " s < " + std::to_string(o.window_s) + " s)");
  }
  if (e.capacity_samples > 100'000'000) config.fail("reidentifier.capacity_s", "must hold at most 1e8 samples");
  e.holdout_branches = static_cast<std::size_t>(config.get_int_in_range("reidentifier.holdout_branches", 1, 1, 1000));
  e.min_relative_improvement =
      config.get_in_range("reidentifier.min_relative_improvement", e.min_relative_improvement, 0.0, 0.99);
  e.max_residual_rms_m = config.get_in_range("reidentifier.max_residual_rms_m", e.max_residual_rms_m, 1e-15, 1.0);
  e.fit.max_solver_time_s = config.get_in_range("reidentifier.max_solver_time_s", e.fit.max_solver_time_s, 1e-4, 60.0);
  // With feedback on, u carries small jitter: reversals smaller than this are not branches.
  e.fit.reversal_dead_band_V =
      config.get_in_range("reidentifier.reversal_dead_band_V", e.fit.reversal_dead_band_V, 0.0, 100.0);
  // The field names of OnlineMemOptions are not the file's: a refusal here would be a bug above.
  e.validate();
  read_model_choice(config, o.models);
  return o;
}

RigLimitsOwn reident_rig_limits(const Config& config, const ReidentOptions& options) {
  const GainPlausibility& p = options.plausibility;
  return RigLimitsOwn::from(config, options.axis, {p.u_min_V, p.u_max_V, 0.0}, false)
      .with_gain(config, p.nominal_gain_m_per_V, p.factor, "reidentifier.plausible_gain_factor");
}

}  // namespace hystloop
