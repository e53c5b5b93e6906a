#include "compensator/compensator_settings.hpp"

#include <algorithm>
#include <cmath>

#include <cstdio>
#include <type_traits>

#include <spdlog/fmt/fmt.h>

#include "models/model_descriptors.hpp"
#include "models/param_config.hpp"
#include "runtime/config_validation.hpp"
#include "runtime/rig_auth_config.hpp"
#include "runtime/stage_config.hpp"

namespace hystloop {
namespace {

TrajectoryShape parse_shape(const Config& config, const std::string& name) {
  if (const auto shape = trajectory_shape_named(name)) return *shape;
  config.fail("trajectory.shape", "must be " + trajectory_shape_choices() + " (got '" + name + "')");
}

// A model's config section (mem.c1, katalenic.input_shaping.kind, ...) read through the model's
// parameter table onto `settings`: the keys are the ones hystloop-identify writes and
// hystloop-model reads. A refused value names the key.
template <class D>
typename D::Params read_model_section(const Config& config, typename D::Settings settings) {
  typename D::Params params;
  validate_config_section(config, std::string(D::name) + ".",
                          [&] { params = params_from_config<D>(config, std::move(settings)); });
  return params;
}

// What model D's section is read onto: D's parameters as configured so far; for PI, whose section
// gives its plays (as identified) or a size and range, the baseline matched to the MEM just read.
template <class D>
typename D::Settings section_settings(const ModelParams& read) {
  if constexpr (std::is_same_v<typename D::Settings, PiSettings>) {
    PiSettings pi;
    pi.matched_to = read.mem;
    return pi;
  } else {
    return D::settings_of(read.*D::in_set);
  }
}

// Every model the compensator is configured with, as one set (of no particular kind).
ModelParamSet configured_models(const CompensatorConfig& c) {
  ModelParamSet set;
  static_cast<ModelParams&>(set) = c.models;
  return set;
}

// compensator.plausible_gain_factor, and the models the file sets (and the one the mode starts
// with) checked against the band every later set is: they reach the actuator as well.
void read_plausibility(const Config& config, CompensatorSettings& s) {
  s.plausible_gain_factor = config.get_in_range("compensator.plausible_gain_factor", s.plausible_gain_factor,
                                                GainPlausibility::kMinFactor, GainPlausibility::kMaxFactor);
  const CompensatorConfig& c = s.control;
  if (!(c.models.linear.gain > 0.0)) {
    config.fail("linear.gain",
                "must be > 0: it is the stage's nominal gain, the one every parameter set is checked "
                "against (compensator.plausible_gain_factor)");
  }
  const GainPlausibility rig = gain_plausibility(s);  // its parts were checked by their own keys
  const std::vector<std::string> keys = config.keys();
  ModelParamSet set = configured_models(c);
  OnlineModels::for_each([&]<class D>() {
    const std::string section = std::string(D::name) + ".";
    const bool in_file =
        std::any_of(keys.begin(), keys.end(), [&](const std::string& k) { return k.rfind(section, 0) == 0; });
    if (!in_file && model_kind_of(c.mode) != D::kind) return;
    set.kind = D::kind;
    validate_config_section(config, "", [&] { require_plausible(set, rig); });
  });
}

// A list of one value per axis (at most kMaxAxes), the rest 0.
AxisPositions per_axis_list(const Config& config, const std::string& key, double lo, double hi) {
  const std::vector<double> v = config.get<std::vector<double>>(key, {});
  if (v.size() > kScanAxes) config.fail(key, "takes at most one value per axis (x, y, z)");
  AxisPositions out{};
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!(v[i] >= lo && v[i] <= hi)) config.fail(key, fmt::format("values must lie in [{}, {}]", lo, hi));
    out[i] = v[i];
  }
  return out;
}

void read_axes_and_scan(const Config& config, CompensatorSettings& s) {
  s.axes = static_cast<int>(config.get_int_in_range("compensator.axes", s.axes, 1, kMaxAxes));
  AxisMatrix c = AxisMatrix::Identity();
  for (const CouplingEntry& k : kCouplingEntries) {  // decoupling.<from>_to_<to>: C(to, from), as the bridge's
    c(k.to, k.from) = config.get_in_range("decoupling." + std::string(k.name), 0.0, -kMaxCoupling, kMaxCoupling);
  }
  validate_config_section(config, "", [&] { s.decoupling = AxisCoupling(s.axes, c); });

  ScanSettings& scan = s.scan;
  const std::string path = config.get<std::string>("scan.path", "none");
  if (path == "none") return;
  if (path == "raster") {
    scan.path = ScanSettings::Path::kRaster;
  } else if (path == "lissajous") {
    scan.path = ScanSettings::Path::kLissajous;
  } else {
    config.fail("scan.path", "must be none, raster or lissajous (got '" + path + "')");
  }
  scan.start_after_s = config.get_in_range("scan.start_after_s", scan.start_after_s, 0.0, 20.0);
  scan.blend_s = config.get_in_range("scan.blend_s", scan.blend_s, 0.0, 10.0);
  scan.decouple = config.get<bool>("scan.decouple", scan.decouple);
  const AxisPositions centre = per_axis_list(config, "scan.centre_m", -1e-3, 1e-3);
  if (scan.path == ScanSettings::Path::kRaster) {
    if (s.axes < 2) config.fail("scan.path", "a raster needs two axes (compensator.axes >= 2)");
    RasterSpec& r = scan.raster;
    r.width_m = config.get_in_range("scan.width_m", 1e-6, 1e-12, 1e-3);
    r.height_m = config.get_in_range("scan.height_m", 1e-6, 0.0, 1e-3);
    r.lines = static_cast<int>(config.get_int_in_range("scan.lines", 64, 2, RasterSpec::kMaxLines));
    r.line_rate_hz = config.get_in_range("scan.line_rate_hz", 50.0, 1e-3, 5000.0);
    r.settle_s = config.get_in_range("scan.settle_s", 0.05, 0.0, 60.0);
    r.corner_s = config.get_non_negative("scan.corner_s", 0.0);
    const std::string slow = config.get<std::string>("scan.slow", "steps");
    if (slow != "steps" && slow != "ramp") config.fail("scan.slow", "must be steps or ramp (got '" + slow + "')");
    r.slow_mode = slow == "ramp" ? SlowMode::kRamp : SlowMode::kSteps;
    r.centre_m = centre;
    RasterSpec checked = r;  // with the corners it will run with
    checked.corner_s = raster_corner_s(r, s.control.stage);
    validate_config_section(config, "scan.", [&] { checked.validate(); });
  } else {
    LissajousSpec& l = scan.lissajous;
    l.amplitude_m = per_axis_list(config, "scan.amplitude_m", 0.0, 1e-3);
    l.frequency_hz = per_axis_list(config, "scan.frequency_hz", 0.0, 5000.0);
    l.phase_rad = per_axis_list(config, "scan.phase_rad", -100.0, 100.0);
    l.duration_s = config.get_in_range("scan.duration_s", 1.0, 1e-3, 3600.0);
    l.centre_m = centre;
    for (int i = s.axes; i < kMaxAxes; ++i) {
      if (l.amplitude_m[static_cast<std::size_t>(i)] != 0.0) {
        config.fail("scan.amplitude_m", "moves axis " + std::string(axis_name(i)) + ", which this stage lacks");
      }
    }
    validate_config_section(config, "scan.", [&] { l.validate(); });
  }
  // What the compensator would refuse at the first sample is refused here, naming the key.
  const double check_s = scan_check_s(scan, raster_corner_s(scan.raster, s.control.stage));
  if (check_s * s.axes > kScanCheckBudget_s) {
    config.fail(scan.path == ScanSettings::Path::kRaster ? "scan.lines" : "scan.duration_s",
                fmt::format("the scan runs {:.3g} s on each of {} axes; a scan is checked whole before it is taken, "
                            "at most {} s of loop time over all axes",
                            check_s, s.axes, kScanCheckBudget_s));
  }
  const double earliest_s = scan.blend_s + static_cast<double>(s.control.horizon_ticks) * s.control.dt_s + 0.01;
  if (scan.start_after_s < earliest_s) {
    config.fail("scan.start_after_s",
                fmt::format("must leave the plan's horizon and the approach (scan.blend_s) before "
                            "the path: at least {:.3g} s",
                            earliest_s));
  }
}

}  // namespace

double raster_corner_s(const RasterSpec& raster, const StageModel& stage) noexcept {
  if (raster.corner_s > 0.0) return raster.corner_s;
  const double c = resonance_corner_s(stage);
  return c > 0.0 ? c : 1e-3;
}

ScanShare scan_share(const ScanSettings& scan, const AxisCoupling& decoupling, int axis, double start_s,
                     double corner_s) {
  const AxisVector row = scan.decouple ? AxisVector(decoupling.inverse_matrix().row(axis).transpose())
                                       : AxisVector(AxisVector::Unit(axis));
  if (scan.path == ScanSettings::Path::kRaster) {
    RasterSpec r = scan.raster;
    r.corner_s = corner_s;
    r.start_s = start_s;
    return ScanShare(r, axis, row);
  }
  LissajousSpec l = scan.lissajous;
  l.start_s = start_s;
  return ScanShare(l, axis, row);
}

double scan_check_s(const ScanSettings& scan, double corner_s) noexcept {
  double path_s = scan.lissajous.duration_s;
  if (scan.path == ScanSettings::Path::kRaster) {
    RasterSpec r = scan.raster;
    r.corner_s = corner_s;
    path_s = raster_duration_s(r);
  }
  return scan.blend_s + path_s;
}

GainPlausibility gain_plausibility(const CompensatorSettings& settings) noexcept {
  GainPlausibility rig;
  rig.nominal_gain_m_per_V = settings.control.models.linear.gain;
  rig.factor = settings.plausible_gain_factor;
  rig.u_min_V = settings.control.u_min_V;
  rig.u_max_V = settings.control.u_max_V;
  return rig;
}

const std::vector<std::string>& compensator_config_keys() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> k = {"compensator.mode",
                                  "compensator.horizon_s",
                                  "compensator.dt_s",
                                  "compensator.run_seconds",
                                  "compensator.sample_queue_capacity",
                                  "compensator.trajectory_check",
                                  "compensator.plan_slew_fraction",
                                  "compensator.servo_slew_reserve",
                                  "compensator.experiment_ramp_V_per_s",
                                  "compensator.swap_worse_ratio",
                                  "compensator.swap_min_excess_m",
                                  "compensator.plausible_gain_factor",
                                  "actuator.u_min_V",
                                  "actuator.u_max_V",
                                  "actuator.slew_V_per_s",
                                  "learning.enabled",
                                  "learning.gain",
                                  "learning.cutoff_hz",
                                  "learning.max_correction_m",
                                  "learning.max_period_s",
                                  "learning.lag_compensated",
                                  "learning.fade_s",
                                  "learning.blend_s",
                                  "learning.ramp_periods",
                                  "learning.hold_params_after",
                                  "rt.priority",
                                  "rt.lock_memory",
                                  "trajectory.shape",
                                  "trajectory.amplitude_m",
                                  "trajectory.offset_m",
                                  "trajectory.frequency_hz",
                                  "trajectory.phase_rad",
                                  "trajectory.blend_s",
                                  "trajectory.corner_s",
                                  "trajectory.shape_if_infeasible",
                                  "trajectory.points_t_s",
                                  "trajectory.points_y_m",
                                  "compensator.axes",
                                  "decoupling.x_to_y",
                                  "decoupling.x_to_z",
                                  "decoupling.y_to_x",
                                  "decoupling.y_to_z",
                                  "decoupling.z_to_x",
                                  "decoupling.z_to_y",
                                  "scan.path",
                                  "scan.start_after_s",
                                  "scan.blend_s",
                                  "scan.decouple",
                                  "scan.width_m",
                                  "scan.height_m",
                                  "scan.lines",
                                  "scan.line_rate_hz",
                                  "scan.slow",
                                  "scan.settle_s",
                                  "scan.corner_s",
                                  "scan.amplitude_m",
                                  "scan.frequency_hz",
                                  "scan.phase_rad",
                                  "scan.duration_s",
                                  "scan.centre_m"};
    OnlineModels::for_each([&]<class D>() { append_config_keys(k, D::name, D::table()); });
    for (std::string& key : stage_config_keys()) k.push_back(std::move(key));
    k.emplace_back("learning.monitor_ratio");
    return k;
  }();
  return keys;
}

CompensatorSettings load_compensator_settings(const Config& config) {
  // Keys of earlier versions say where their setting went.
  for (const std::string& key : config.keys()) {
    if (key.rfind("feedback.", 0) == 0) {
      config.fail(key,
                  "the servo runs in the bridge now, beside the sensor: set servo.kp, servo.ki, servo.kd in "
                  "the bridge's config (deploy/config/bridge.yaml) or at run time with `hystloop-ctl gains`");
    }
  }
  if (config.has("compensator.lead_ticks")) {
    config.fail("compensator.lead_ticks",
                "replaced by compensator.horizon_s: commands are planned that far ahead "
                "of the bridge's clock");
  }
  std::vector<std::string> known = compensator_config_keys();
  known.insert(known.end(), rig_auth_config_keys().begin(), rig_auth_config_keys().end());  // read by main
  config.check_no_unknown_keys(known);
  CompensatorSettings s;
  CompensatorConfig& c = s.control;
  const std::string mode = config.get<std::string>("compensator.mode", "mem");
  validate_config_section(config, "", [&] { c.mode = parse_feedforward_mode(mode, "compensator.mode"); });
  c.dt_s = config.get_in_range("compensator.dt_s", c.dt_s, 1e-6, 1.0);
  s.run_seconds = config.get_non_negative("compensator.run_seconds", s.run_seconds);
  s.sample_queue_capacity = static_cast<int>(
      config.get_int_in_range("compensator.sample_queue_capacity", s.sample_queue_capacity, 16, 100000));
  const std::string check = config.get<std::string>("compensator.trajectory_check", "thread");
  if (check != "thread" && check != "inline") {
    config.fail("compensator.trajectory_check", "expected thread or inline, got '" + check + "'");
  }
  s.check_on_thread = check == "thread";
  s.rt_priority = static_cast<int>(config.get_int_in_range("rt.priority", s.rt_priority, 0, 99));
  s.lock_memory = config.get<bool>("rt.lock_memory", s.lock_memory);

  // Every model's section. MEM's first: PI's baseline is matched to the MEM this file configures.
  c.models.mem = read_model_section<MemDescriptor>(config, c.models.mem);
  OnlineModels::for_each([&]<class D>() {
    if constexpr (D::kind != ModelKind::mem) {
      c.models.*D::in_set = read_model_section<D>(config, section_settings<D>(c.models));
    }
  });

  // The actuator as the bridge limits it: the plan stays inside it (held against the bridge's at run time,
  // runtime/rig_check.hpp).
  c.u_min_V = config.get<double>("actuator.u_min_V", c.u_min_V);
  c.u_max_V = config.get<double>("actuator.u_max_V", c.u_max_V);
  c.slew_V_per_s = config.get_positive("actuator.slew_V_per_s", c.slew_V_per_s);
  c.plan_slew_fraction = config.get_in_range("compensator.plan_slew_fraction", c.plan_slew_fraction, 0.05, 1.0);
  c.servo_slew_reserve =
      config.get_in_range("compensator.servo_slew_reserve", c.servo_slew_reserve, 0.0, c.plan_slew_fraction - 0.05);
  c.experiment_ramp_V_per_s = config.get_positive("compensator.experiment_ramp_V_per_s", c.experiment_ramp_V_per_s);
  c.swap_review.worse_ratio = config.get<double>("compensator.swap_worse_ratio", c.swap_review.worse_ratio);
  c.swap_review.min_excess_m = config.get<double>("compensator.swap_min_excess_m", c.swap_review.min_excess_m);
  c.swap_review.validate();

  c.stage = read_stage_model(config, c.stage, c.dt_s);

  LearningConfig& l = c.learning;
  l.enabled = config.get<bool>("learning.enabled", l.enabled);
  l.gain = config.get_in_range("learning.gain", l.gain, 1e-3, 1.0);
  // The default filter, never above a quarter of the tick rate (what the learner's filter can be).
  l.cutoff_hz = config.get_positive("learning.cutoff_hz", std::min(l.cutoff_hz, 0.25 / c.dt_s));
  l.max_correction_m = config.get_positive("learning.max_correction_m", l.max_correction_m);
  l.max_period_s = config.get_positive("learning.max_period_s", l.max_period_s);
  l.lag_compensated = config.get<bool>("learning.lag_compensated", l.lag_compensated);
  l.fade_s = config.get_positive("learning.fade_s", l.fade_s);
  l.blend_s = config.get_in_range("learning.blend_s", l.blend_s, 0.0, 1.0);
  l.ramp_periods = config.get_in_range("learning.ramp_periods", l.ramp_periods, 0.0, 100.0);
  l.hold_params_after = config.get_int_in_range("learning.hold_params_after", l.hold_params_after, 0, 1'000'000);
  l.monitor_ratio = config.get_non_negative("learning.monitor_ratio", l.monitor_ratio);
  validate_config_section(config, "", [&] { l.validate(c.dt_s); });  // its fields are named learning.*

  const double horizon_s =
      config.get_in_range("compensator.horizon_s", static_cast<double>(c.horizon_ticks) * c.dt_s, 2.0 * c.dt_s,
                          static_cast<double>(CompensatorConfig::kMaxHorizonTicks) * c.dt_s);
  c.horizon_ticks = static_cast<std::int64_t>(std::llround(horizon_s / c.dt_s));
  validate_config_section(config, "", [&] { c.validate(); });
  read_plausibility(config, s);

  TrajectorySpec& t = s.trajectory;
  t.shape = parse_shape(config, config.get<std::string>("trajectory.shape", "hold"));
  t.amplitude_m = config.get_in_range("trajectory.amplitude_m", 0.0, -1e-3, 1e-3);
  t.offset_m = config.get_in_range("trajectory.offset_m", 0.0, -1e-3, 1e-3);
  t.frequency_hz = config.get_in_range("trajectory.frequency_hz", 1.0, 1e-6, 1e4);
  t.phase_rad = config.get<double>("trajectory.phase_rad", 0.0);
  t.blend_s = config.get_in_range("trajectory.blend_s", 0.5, 0.0, 3600.0);
  t.corner_s = config.get_non_negative("trajectory.corner_s", 0.0);
  t.shape_if_infeasible = config.get<bool>("trajectory.shape_if_infeasible", false);
  const auto pt = config.get<std::vector<double>>("trajectory.points_t_s", {});
  const auto py = config.get<std::vector<double>>("trajectory.points_y_m", {});
  if (pt.size() != py.size()) config.fail("trajectory.points_y_m", "needs as many values as trajectory.points_t_s");
  if (pt.size() > TrajectorySpec::kMaxPoints) config.fail("trajectory.points_t_s", "too many points");
  t.n_points = pt.size();
  for (std::size_t i = 0; i < pt.size(); ++i) {
    t.points_t_s[i] = pt[i];
    t.points_y_m[i] = py[i];
  }
  validate_config_section(config, "", [&] { t.validate(); });
  read_axes_and_scan(config, s);
  for (int axis = 0; axis < s.axes; ++axis) {
    s.rig_limits.push_back(
        RigLimitsOwn::from(config, axis, {c.u_min_V, c.u_max_V, c.slew_V_per_s}, true)
            .with_gain(config, c.models.linear.gain, s.plausible_gain_factor, "compensator.plausible_gain_factor"));
  }
  return s;
}

void merge_params_file(Config& config, const std::filesystem::path& snippet) {
  const Config params = Config::load_file(snippet);
  for (const std::string& key : params.keys()) {
    // hystloop-identify --model banning writes the bridge's simulated stage beside the
    // compensator's stage section: that one is the bridge's.
    if (key.rfind("banning.", 0) == 0) continue;
    std::string value;
    try {
      value = params.get<std::string>(key);
    } catch (const ConfigError&) {  // a list: thresholds, weights, coefficients
      value = "[" + format_list(params.get<std::vector<double>>(key)) + "]";
    }
    std::string assignment = key;  // (appended, not key + "=" + value: GCC 12 warns falsely on that)
    assignment.append(1, '=').append(value);
    config.apply_override(assignment);
  }
}

std::vector<std::string> describe(const CompensatorSettings& s) {
  const CompensatorConfig& c = s.control;
  const TrajectorySpec& t = s.trajectory;
  std::vector<std::string> lines;
  lines.push_back(
      fmt::format("compensator: mode {}, plans {} ticks ({:.4g} s) ahead, dt {} s, trajectories checked {}{}",
                  to_string(c.mode), c.horizon_ticks, static_cast<double>(c.horizon_ticks) * c.dt_s, c.dt_s,
                  s.check_on_thread ? "on their own thread" : "inline (replayable exactly)",
                  s.run_seconds > 0 ? fmt::format(", stops after {} s", s.run_seconds) : std::string()));
  ModelParamSet models = configured_models(c);
  OnlineModels::for_each([&]<class D>() {
    models.kind = D::kind;
    lines.push_back(describe_model(models));
  });
  lines.push_back(fmt::format(
      "actuator: u in [{}, {}] V, slew {:.4g} V/s (an experiment uses at most {:.0f} % of it, a trajectory {:.0f} %)",
      c.u_min_V, c.u_max_V, c.slew_V_per_s, 100.0 * c.plan_slew_fraction, 100.0 * c.tracking_slew_fraction()));
  if (c.stage.has_dynamics()) {
    lines.push_back(
        "stage: " + describe_stage(c.stage, c.dt_s) + ", " +
        (c.stage.order == BanningOrder::kHysteresisThenStage ? "hysteresis then stage" : "stage then hysteresis"));
  } else {
    lines.push_back("stage: none (the hysteresis inverse alone)");
  }
  const LearningConfig learning = learning_for_stage(c.learning, c.stage, c.dt_s);
  const double feature_hz = lowest_linear_feature_hz(c.stage, c.dt_s);
  const bool by_band = c.stage.known_to_hz * kLearningShareOfKnownBand > kLearningShareOfResonance * feature_hz;
  const std::string filter =
      learning.cutoff_hz >= c.learning.cutoff_hz ? fmt::format("{} Hz", learning.cutoff_hz)
      : by_band                                  ? fmt::format(
                                                       "{:.4g} Hz, {} of the band the stage's model is known to, stage.known_to_hz {:.4g} Hz "
                                                                                        "(learning.cutoff_hz {} Hz)",
                                                       learning.cutoff_hz, kLearningShareOfKnownBand, c.stage.known_to_hz, c.learning.cutoff_hz)
                : fmt::format(
                      "{:.4g} Hz, {} of the stage's lowest mode or anti-resonance {:.4g} Hz (learning.cutoff_hz "
                      "{} Hz)",
                      learning.cutoff_hz, kLearningShareOfResonance, feature_hz, c.learning.cutoff_hz);
  lines.push_back(fmt::format("learning: {} (gain {}, filter {}, |correction| <= {:.3g} m, periods up to {} s{})",
                              c.learning.enabled ? "on for periodic references" : "off", c.learning.gain, filter,
                              c.learning.max_correction_m, c.learning.max_period_s,
                              c.learning.lag_compensated ? ", lag-compensated" : ""));
  lines.push_back(fmt::format("rt: priority {}, lock_memory {}", s.rt_priority, s.lock_memory));
  lines.push_back(fmt::format("trajectory: {} amplitude {:.4g} m, offset {:.4g} m, {} Hz, blend {} s, {} points",
                              to_string(t.shape), t.amplitude_m, t.offset_m, t.frequency_hz, t.blend_s, t.n_points));
  if (s.axes > 1) {
    lines.push_back(fmt::format(
        "axes: {}, one control law each (trajectories, parameter sets and experiments name theirs); coupling to "
        "cancel{}",
        s.axes, describe_coupling(s.decoupling.matrix(), s.axes)));
  }
  const ScanSettings& sc = s.scan;
  if (sc.path == ScanSettings::Path::kRaster) {
    const RasterSpec& r = sc.raster;
    lines.push_back(fmt::format(
        "scan: raster {:.4g} x {:.4g} m, {} lines at {} lines/s, slow axis {}, {} {} s after the first sample{}",
        r.width_m, r.height_m, r.lines, r.line_rate_hz, r.slow_mode == SlowMode::kRamp ? "ramping" : "stepping",
        sc.decouple ? "decoupled," : "not decoupled,", sc.start_after_s,
        r.corner_s > 0.0 ? fmt::format(", corners {} s", r.corner_s) : std::string()));
  } else if (sc.path == ScanSettings::Path::kLissajous) {
    const LissajousSpec& l = sc.lissajous;
    lines.push_back(fmt::format("scan: Lissajous, amplitudes {} m at {} Hz for {} s, {} {} s after the first sample",
                                format_list(l.amplitude_m), format_list(l.frequency_hz), l.duration_s,
                                sc.decouple ? "decoupled," : "not decoupled,", sc.start_after_s));
  }
  return lines;
}

}  // namespace hystloop
