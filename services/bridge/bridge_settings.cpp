#include "bridge/bridge_settings.hpp"

#include <cstdint>
#include <climits>
#include <algorithm>
#include <cmath>
#include <span>

#include <spdlog/fmt/fmt.h>

#include "loop/command_buffer.hpp"
#include "models/model_descriptors.hpp"
#include "models/param_config.hpp"
#include "runtime/config_validation.hpp"
#include "runtime/rig_auth_config.hpp"
#include "runtime/stage_config.hpp"

namespace hystloop {
namespace {

// An axis's own keys: actuator.<field> and servo.<field> for x, actuator.y.<field> ... for y and z.
constexpr const char* kAxisActuatorKeys[] = {"u_min_V",           "u_max_V",        "slew_V_per_s",  "safe_u_V",
                                             "safe_ramp_V_per_s", "position_min_m", "position_max_m"};
constexpr const char* kAxisServoKeys[] = {
    "kp", "ki", "kd", "nominal_gain_m_per_V", "d_filter_hz", "notch_hz", "notch_q", "notch2_hz", "notch2_q"};

std::string axis_prefix(const char* section, int axis) { return axis_field(section, axis); }
std::string axis_key(const char* section, int axis, const char* field) { return axis_prefix(section, axis) + field; }

bool has_axis_keys(const Config& config, const char* section, int axis, std::span<const char* const> fields) {
  return std::any_of(fields.begin(), fields.end(),
                     [&](const char* f) { return config.has(axis_key(section, axis, f)); });
}

// Axis `axis`'s actuator (actuator.* for x, actuator.y.* ...), each key absent taken from `a`.
ActuatorLimits load_limits(const Config& config, int axis, ActuatorLimits a) {
  const std::string p = axis_prefix("actuator.", axis);
  a.u_min_V = config.get_in_range(p + "u_min_V", a.u_min_V, -1e4, 1e4);
  a.u_max_V = config.get_in_range(p + "u_max_V", a.u_max_V, -1e4, 1e4);
  a.slew_V_per_s = config.get_positive(p + "slew_V_per_s", a.slew_V_per_s);
  a.safe_u_V = config.get_in_range(p + "safe_u_V", a.safe_u_V, -1e4, 1e4);
  a.safe_ramp_V_per_s = config.get_positive(p + "safe_ramp_V_per_s", a.safe_ramp_V_per_s);
  // Soft position limits: absent, none (a stage's sensor range is the lab's to give).
  if (config.has(p + "position_min_m")) a.position_min_m = config.get_in_range(p + "position_min_m", 0.0, -1.0, 1.0);
  if (config.has(p + "position_max_m")) a.position_max_m = config.get_in_range(p + "position_max_m", 0.0, -1.0, 1.0);
  try {
    a.validate();
  } catch (const ParameterError& e) {
    config.fail(axis_field(e.field(), axis), e.reason());
  }
  return a;
}

// Axis `axis`'s servo (servo.* for x, servo.y.* ...), each key absent taken from `g`; its output
// range the axis's actuator's `a`.
FeedbackGains load_servo(const Config& config, int axis, FeedbackGains g, const ActuatorLimits& a, double rate_hz) {
  const std::string p = axis_prefix("servo.", axis);
  g.kp = config.get_non_negative(p + "kp", g.kp);
  g.ki = config.get_non_negative(p + "ki", g.ki);
  g.kd = config.get_non_negative(p + "kd", g.kd);
  g.nominal_gain_m_per_V = config.get_positive(p + "nominal_gain_m_per_V", g.nominal_gain_m_per_V);
  g.d_filter_hz = config.get_positive(p + "d_filter_hz", g.d_filter_hz);
  g.notch_hz = config.get_non_negative(p + "notch_hz", g.notch_hz);
  // Checked here even without a notch: a Q the file gives is meant to be used.
  g.notch_q = config.get_in_range(p + "notch_q", g.notch_q, kNotchMinQ, kNotchMaxQ);
  g.notch2_hz = config.get_non_negative(p + "notch2_hz", g.notch2_hz);
  g.notch2_q = config.get_in_range(p + "notch2_q", g.notch2_q, kNotchMinQ, kNotchMaxQ);
  g.u_min_V = a.u_min_V;
  g.u_max_V = a.u_max_V;
  g.tick_rate_hz = rate_hz;
  // Its fields are named servo.* (servo.y.*); the gains within the plausibility bounds (loop/feedback.hpp).
  try {
    g.check_bounds();
  } catch (const ParameterError& e) {
    config.fail(axis_field(e.field(), axis), e.reason());
  }
  return g;
}

// The series plant's hysteresis: plant.hysteresis.kind names the model; every model's section
// plant.hysteresis.<kind>.* is read and validated whatever the kind (as banning.* and ro.* are
// whatever the backend: one file serves them all). MEM's, PI's, Katalenic's and the linear
// spring's through their parameter tables (the names hystloop-identify writes), but for their
// lists: PI is the project's baseline (count plays over range_V, weights matched to the default
// MEM) and Katalenic's shaping is linear or tanh, as a list could not be shown for every kind in
// one file and still be refused when malformed. Explicit PI weights and polynomial shaping run in
// the in-process simulation (SimulatedStageConfig::hysteresis).
constexpr const char* kColemanHodgdonKeys[] = {"a", "b", "alpha", "s_max"};
constexpr const char* kBoucWenKeys[] = {"d", "alpha", "beta", "gamma", "n", "rk4_substeps"};
const std::string kHysteresisPrefix = "plant.hysteresis.";

HysteresisPlantSpec load_plant_hysteresis(const Config& config) {
  HysteresisPlantSpec h;
  const std::string kind_key = kHysteresisPrefix + "kind";
  validate_config_section(config, kHysteresisPrefix, [&] {
    h.kind = hysteresis_plant_kind_from_name(config.get<std::string>(kind_key, "coleman_hodgdon"), "kind");
  });
  const std::string ch = kHysteresisPrefix + "coleman_hodgdon.";
  ColemanHodgdonParams& c = h.coleman_hodgdon;
  c.a = config.get<double>(ch + "a", c.a);
  c.b = config.get<double>(ch + "b", c.b);
  c.alpha = config.get<double>(ch + "alpha", c.alpha);
  c.s_max = config.get<double>(ch + "s_max", c.s_max);
  validate_config_section(config, ch, [&] { c.validate(); });
  const std::string mem = kHysteresisPrefix + "mem";
  validate_config_section(config, mem + ".", [&] {
    h.mem = params_from_config<MemDescriptor>(config, h.mem, mem);
    h.mem.validate();
  });
  h.mem_reversal_deadband_V = config.get_non_negative(kHysteresisPrefix + "mem_reversal_deadband_V", 0.0);
  const std::string bw = kHysteresisPrefix + "bouc_wen.";
  BoucWenParams& b = h.bouc_wen;
  b.d = config.get<double>(bw + "d", b.d);
  b.alpha = config.get<double>(bw + "alpha", b.alpha);
  b.beta = config.get<double>(bw + "beta", b.beta);
  b.gamma = config.get<double>(bw + "gamma", b.gamma);
  b.n = config.get<double>(bw + "n", b.n);
  b.rk4_substeps = config.get<int>(bw + "rk4_substeps", b.rk4_substeps);
  validate_config_section(config, bw, [&] { b.validate(); });
  const std::string pi = kHysteresisPrefix + "pi";
  validate_config_section(config, pi + ".", [&] { h.pi = params_from_config<PiDescriptor>(config, PiSettings{}, pi); });
  const std::string kat = kHysteresisPrefix + "katalenic";
  validate_config_section(config, kat + ".", [&] {
    h.katalenic = params_from_config<KatalenicDescriptor>(config, h.katalenic, kat);
    h.katalenic.validate();
  });
  const std::string lin = kHysteresisPrefix + "linear";
  validate_config_section(config, lin + ".", [&] {
    h.linear = params_from_config<LinearDescriptor>(config, h.linear, lin);
    h.linear.validate();
  });
  return h;
}

}  // namespace

const ActuatorLimits& BridgeSettings::limits_of(int axis) const noexcept {
  const auto& own = axis_limits[static_cast<std::size_t>(axis)];
  return axis > 0 && own ? *own : limits;
}

const FeedbackGains& BridgeSettings::servo_of(int axis) const noexcept {
  const auto& own = axis_servo[static_cast<std::size_t>(axis)];
  return axis > 0 && own ? *own : servo;
}

std::array<ActuatorLimits, kMaxAxes> BridgeSettings::axes_limits() const noexcept {
  std::array<ActuatorLimits, kMaxAxes> out{};
  for (int i = 0; i < kMaxAxes; ++i) out[static_cast<std::size_t>(i)] = limits_of(i);
  return out;
}

std::array<FeedbackGains, kMaxAxes> BridgeSettings::axes_servo() const noexcept {
  std::array<FeedbackGains, kMaxAxes> out{};
  for (int i = 0; i < kMaxAxes; ++i) out[static_cast<std::size_t>(i)] = servo_of(i);
  return out;
}

std::array<double, kMaxAxes> BridgeSettings::safe_voltages() const noexcept {
  std::array<double, kMaxAxes> out{};
  for (int i = 0; i < kMaxAxes; ++i) out[static_cast<std::size_t>(i)] = limits_of(i).safe_u_V;
  return out;
}

double BridgeSettings::longest_safe_ramp_s() const noexcept {
  double longest = 0.0;
  for (int i = 0; i < axes; ++i) longest = std::max(longest, limits_of(i).longest_safe_ramp_s());
  return longest;
}

std::string real_time_refused(const std::string& what) {
  return "rt.required: " + what +
         ": the bridge does not run a hardware backend without real time (missed ticks hold stale voltages). Grant "
         "it: run as root, or `sudo setcap cap_sys_nice,cap_ipc_lock+ep` on hystloop-bridge, or rtprio 99 and "
         "memlock unlimited for the user (/etc/security/limits.d/), or LimitRTPRIO=99 and LimitMEMLOCK=infinity "
         "in its systemd unit; or waive it with rt.required: false (docs/TIMING.md, \"Real-time host\")";
}

AxisMatrix default_stage_coupling() noexcept { return flexure_stage(kMaxAxes).coupling.matrix(); }

MultiAxisStageConfig multi_axis_stage(const BridgeSettings& settings) {
  MultiAxisStageConfig config;
  config.coupling = AxisCoupling(settings.axes, settings.coupling);
  const PlantKind plant = parse_plant_kind(settings.backend, "bridge.backend");
  for (std::size_t i = 0; i < config.axis.size(); ++i) {
    config.axis[i] = settings.stage;
    config.axis[i].plant = plant;
    config.axis[i].seed = settings.stage.seed + i;
  }
  return config;
}

const std::vector<std::string>& bridge_config_keys() {
  static const std::vector<std::string> keys = {"bridge.backend",
                                                "bridge.axes",
                                                "coupling.x_to_y",
                                                "coupling.x_to_z",
                                                "coupling.y_to_x",
                                                "coupling.y_to_z",
                                                "coupling.z_to_x",
                                                "coupling.z_to_y",
                                                "bridge.rate_hz",
                                                "bridge.noise_rms_m",
                                                "bridge.seed",
                                                "bridge.drift_fraction",
                                                "bridge.drift_start_s",
                                                "bridge.drift_duration_s",
                                                "bridge.auto_arm",
                                                "actuator.rearm_after_trip_s",
                                                "bridge.degraded_late_fraction",
                                                "bridge.run_seconds",
                                                "bridge.command_queue_capacity",
                                                "bridge.block_ticks",
                                                "bridge.max_lead_s",
                                                "bridge.max_stall_s",
                                                "bridge.oscillation_rms_V",
                                                "bridge.oscillation_above_hz",
                                                "bridge.oscillation_hold_s",
                                                "actuator.watchdog_s",
                                                "rt.ticks_per_wake",
                                                "rt.priority",
                                                "rt.io_priority",
                                                "rt.lock_memory",
                                                "rt.cpu",
                                                "rt.required"};
  static const std::vector<std::string> all = [] {
    std::vector<std::string> k = keys;
    // actuator.* and servo.* for axis x, actuator.y.*, servo.y.* ... for the others.
    for (int axis = 0; axis < kMaxAxes; ++axis) {
      for (const char* field : kAxisActuatorKeys) k.push_back(axis_key("actuator.", axis, field));
      for (const char* field : kAxisServoKeys) k.push_back(axis_key("servo.", axis, field));
    }
    k.insert(k.end(), comedi_config_keys().begin(), comedi_config_keys().end());
    append_config_keys(k, BanningDescriptor::name, BanningDescriptor::table());  // the simulated stage
    append_config_keys(k, "ro", MemDescriptor::table());                         // the Ramberg-Osgood plant
    // The series plant: plant.hysteresis.<kind>.* and plant.stage.*.
    k.push_back(kHysteresisPrefix + "kind");
    for (const char* f : kColemanHodgdonKeys) k.push_back(kHysteresisPrefix + "coleman_hodgdon." + f);
    append_config_keys(k, kHysteresisPrefix + "mem", MemDescriptor::table());
    k.push_back(kHysteresisPrefix + "mem_reversal_deadband_V");
    for (const char* f : {"count", "range_V"}) k.push_back(kHysteresisPrefix + "pi." + f);
    for (const auto& row : KatalenicDescriptor::table()) {
      if (!std::string_view(row.name).ends_with("coefficients")) {
        k.push_back(kHysteresisPrefix + "katalenic." + std::string(row.name));
      }
    }
    for (const char* f : kBoucWenKeys) k.push_back(kHysteresisPrefix + "bouc_wen." + f);
    append_config_keys(k, kHysteresisPrefix + "linear", LinearDescriptor::table());
    for (std::string& key : linear_stage_keys("plant.stage")) k.push_back(std::move(key));
    return k;
  }();
  return all;
}

BridgeSettings load_bridge_settings(const Config& config) {
  std::vector<std::string> known = bridge_config_keys();
  known.insert(known.end(), rig_auth_config_keys().begin(), rig_auth_config_keys().end());  // read by main
  config.check_no_unknown_keys(known);
  BridgeSettings s;
  s.backend = config.get<std::string>("bridge.backend", s.backend);
  if (s.backend != "sim" && s.backend != "ro" && s.backend != "series" && s.backend != "comedi") {
    config.fail("bridge.backend", "must be sim, ro, series or comedi (got '" + s.backend + "')");
  }
  s.axes = static_cast<int>(config.get_int_in_range("bridge.axes", s.axes, 1, kMaxAxes));
  for (const CouplingEntry& c : kCouplingEntries) {  // coupling.<from>_to_<to>: C(to, from)
    s.coupling(c.to, c.from) =
        config.get_in_range("coupling." + std::string(c.name), s.coupling(c.to, c.from), -kMaxCoupling, kMaxCoupling);
  }
  // Validated whatever the backend (one config serves both); each axis's channels are required by comedi only.
  s.rate_hz = config.get_in_range("bridge.rate_hz", s.rate_hz, 1.0, 100000.0);
  s.comedi = load_comedi_settings(config, s.axes, s.backend == "comedi", s.rate_hz);
  s.auto_arm = config.get<bool>("bridge.auto_arm", s.auto_arm);
  s.rearm_after_trip_s = config.get_in_range("actuator.rearm_after_trip_s", s.rearm_after_trip_s, 0.0, 3600.0);
  s.degraded_late_fraction = config.get_in_range("bridge.degraded_late_fraction", s.degraded_late_fraction, 0.0, 1.0);
  s.run_seconds = config.get_non_negative("bridge.run_seconds", s.run_seconds);
  s.command_queue_capacity =
      static_cast<int>(config.get_int_in_range("bridge.command_queue_capacity", s.command_queue_capacity, 16, 100000));
  s.block_ticks = static_cast<int>(config.get_int_in_range("bridge.block_ticks", s.block_ticks, 1, 1000));
  s.max_stall_s = config.get_in_range("bridge.max_stall_s", s.max_stall_s, 1.0 / s.rate_hz, 1.0);
  OscillationLimit& osc = s.oscillation;
  osc.rms_V = config.get_non_negative("bridge.oscillation_rms_V", osc.rms_V);
  osc.above_hz = config.get_positive("bridge.oscillation_above_hz", osc.above_hz);
  osc.hold_s = config.get_positive("bridge.oscillation_hold_s", osc.hold_s);
  try {
    osc.validate(s.rate_hz);
  } catch (const ParameterError& e) {
    config.fail(e.field(), e.reason());
  }
  s.max_lead_s = config.get_in_range("bridge.max_lead_s", s.max_lead_s, 2.0 / s.rate_hz,
                                     static_cast<double>(CommandBuffer::kCapacityTicks) / s.rate_hz);

  SimulatedStageConfig& st = s.stage;
  st.noise_rms_m = config.get_in_range("bridge.noise_rms_m", st.noise_rms_m, 0.0, 1e-6);
  st.seed = static_cast<std::uint64_t>(config.get_int_in_range("bridge.seed", 1, 0, INT64_MAX));
  st.drift_fraction = config.get_in_range("bridge.drift_fraction", st.drift_fraction, -0.5, 1.0);
  st.drift_start_s = config.get_non_negative("bridge.drift_start_s", st.drift_start_s);
  st.drift_duration_s = config.get_positive("bridge.drift_duration_s", st.drift_duration_s);
  // The keys hystloop-identify --model banning writes, through the same table.
  validate_config_section(config, "banning.",
                          [&] { st.banning = params_from_config<BanningDescriptor>(config, st.banning); });
  // The Ramberg-Osgood plant is a MEM: its keys are the MEM's (ro.c1, ro.c2, ro.c3).
  validate_config_section(
      config, "ro.", [&] { st.ramberg_osgood = params_from_config<MemDescriptor>(config, st.ramberg_osgood, "ro"); });
  // The series plant (plant.*), sampled at the bridge's tick; validated whatever the backend, as above.
  st.hysteresis = load_plant_hysteresis(config);
  st.linear = read_linear_stage(config, "plant.stage", st.linear);
  st.tick_s = s.dt_s();
  validate_config_section(config, "", [&] { st.validate(); });
  validate_config_section(config, "", [&] {
    SimulatedStageConfig series = st;
    series.plant = PlantKind::kSeries;
    series.validate();
  });
  if (s.axes > 1 && s.backend != "comedi") {
    // The coupling's conditioning, the seeds: everything the XY(Z) stage checks, named by its field.
    validate_config_section(config, "", [&] { multi_axis_stage(s).validate(); });
  }

  s.limits = load_limits(config, 0, s.limits);
  s.limits.watchdog_s = config.get_in_range("actuator.watchdog_s", s.limits.watchdog_s, 1e-5, 10.0);
  validate_config_section(config, "", [&] { s.limits.validate(); });
  if (s.limits.watchdog_s < 2.0 * s.dt_s()) {
    config.fail("actuator.watchdog_s", "must be at least two ticks (" + std::to_string(2.0 * s.dt_s()) + " s)");
  }
  s.servo = load_servo(config, 0, s.servo, s.limits, s.rate_hz);
  for (int axis = 1; axis < kMaxAxes; ++axis) {
    const bool own_actuator = has_axis_keys(config, "actuator.", axis, kAxisActuatorKeys);
    const bool own_servo = has_axis_keys(config, "servo.", axis, kAxisServoKeys);
    if (!own_actuator && !own_servo) continue;
    if (axis >= s.axes) {
      const std::string section = own_actuator ? "actuator." : "servo.";
      config.fail(section + std::string(axis_name(axis)),
                  "the stage has " + std::to_string(s.axes) + " ax" + (s.axes == 1 ? "is" : "es") +
                      " (bridge.axes): there is no axis " + std::string(axis_name(axis)));
    }
    const auto at = static_cast<std::size_t>(axis);
    const ActuatorLimits a = load_limits(config, axis, s.limits);
    if (own_actuator) s.axis_limits[at] = a;
    // An axis's servo clamps to its own actuator's range, whether its gains are its own or x's.
    s.axis_servo[at] = load_servo(config, axis, s.servo, a, s.rate_hz);
  }
  s.stop_ramp_timeout_s = s.longest_safe_ramp_s() + kStopRampMargin_s;

  s.rt.ticks_per_wake = static_cast<int>(config.get_int_in_range("rt.ticks_per_wake", s.rt.ticks_per_wake, 1, 1000));
  if (s.rt.ticks_per_wake > s.block_ticks) {
    config.fail("rt.ticks_per_wake", "must not exceed bridge.block_ticks (" + std::to_string(s.block_ticks) +
                                         "): a block is published when its last tick has run");
  }
  if (s.backend == "comedi" && s.rt.ticks_per_wake != 1) {
    config.fail("rt.ticks_per_wake",
                "must be 1 with bridge.backend comedi: a card's output cannot run ticks back to back");
  }
  s.rt.priority = static_cast<int>(config.get_int_in_range("rt.priority", s.rt.priority, 0, 99));
  s.rt.io_priority = static_cast<int>(config.get_int_in_range("rt.io_priority", s.rt.io_priority, 0, 99));
  if (s.rt.io_priority > 0 && s.rt.io_priority >= s.rt.priority) {
    config.fail("rt.io_priority", "must be below rt.priority, so the I/O thread never preempts the clock");
  }
  s.rt.lock_memory = config.get<bool>("rt.lock_memory", s.rt.lock_memory);
  s.rt.cpu = static_cast<int>(config.get_int_in_range("rt.cpu", s.rt.cpu, -1, 1023));
  s.rt.required = config.get<bool>("rt.required", s.backend == "comedi");
  if (s.rt.required && (s.rt.priority == 0 || !s.rt.lock_memory)) {
    config.fail("rt.required",
                "real time is required (the default for a hardware backend): set rt.priority 1..99 and "
                "rt.lock_memory: true, or waive it with rt.required: false (docs/TIMING.md, \"Real-time host\")");
  }
  return s;
}

std::vector<std::string> describe(const BridgeSettings& s) {
  const auto& st = s.stage;
  std::vector<std::string> lines;
  if (s.axes > 1 && s.backend == "comedi") {
    lines.push_back(
        fmt::format("axes: {} on one clock and one safe state, a channel pair each (comedi below)", s.axes));
  } else if (s.axes > 1) {
    lines.push_back(fmt::format("axes: {} on one clock and one safe state; noise seeds {}..{}; coupling{}", s.axes,
                                s.stage.seed, s.stage.seed + static_cast<std::uint64_t>(s.axes) - 1,
                                describe_coupling(s.coupling, s.axes)));
  }
  lines.push_back(fmt::format(
      "bridge: backend {}, rate {} Hz, noise {:.3g} m RMS, seed {}, drift {:+.3g} over {} s from {} s, {}{}", s.backend,
      s.rate_hz, st.noise_rms_m, st.seed, st.drift_fraction, st.drift_duration_s, st.drift_start_s,
      s.auto_arm ? "auto-arm" : "arm via HX_CONTROL",
      s.run_seconds > 0 ? fmt::format(", stops after {} s", s.run_seconds) : std::string()));
  // Axis x's actuator and servo, then each other axis's where it has its own ("as x" otherwise).
  const auto axis_label = [&](const char* section, int axis) {
    return s.axes == 1 ? std::string(section) : fmt::format("{} {}", section, axis_name(axis));
  };
  for (int axis = 0; axis < s.axes; ++axis) {
    const ActuatorLimits& a = s.limits_of(axis);
    if (axis > 0 && !s.axis_limits[static_cast<std::size_t>(axis)]) {
      lines.push_back(axis_label("actuator", axis) + ": as x");
      continue;
    }
    lines.push_back(fmt::format("{}: range [{}, {}] V, slew {} V/s, safe {} V reached at {} V/s",
                                axis_label("actuator", axis), a.u_min_V, a.u_max_V, a.slew_V_per_s, a.safe_u_V,
                                a.safe_ramp_rate_V_per_s()));
  }
  lines.push_back(
      fmt::format("watchdog {} s for the stage; stop: every axis ramps to its safe voltage (the longest "
                  "ramp at most {:.4g} s) within {} s",
                  s.limits.watchdog_s, s.longest_safe_ramp_s(), s.stop_ramp_timeout_s));
  if (s.backend == "comedi") {
    for (std::string& line : describe(s.comedi)) lines.push_back(std::move(line));
  } else if (s.backend == "sim") {
    lines.push_back("banning: " + BanningDescriptor::summary_of(st.banning));
  } else if (s.backend == "series") {
    const DiscreteLinearStage d = discretise(st.linear, st.tick_s);
    lines.push_back(
        fmt::format("plant: {} hysteresis, then a linear stage of {} states (unit DC gain) with "
                    "{:.4g} s of input delay ({:.4g} ticks)",
                    to_string(st.hysteresis.kind), d.states(), st.linear.delay_s, st.linear.delay_s / st.tick_s));
  } else {
    lines.push_back("ro: " + MemDescriptor::summary_of(st.ramberg_osgood));
  }
  for (int axis = 0; axis < s.axes; ++axis) {
    const FeedbackGains& g = s.servo_of(axis);
    lines.push_back(fmt::format("{}: kp {}, ki {} 1/s, kd {} s on y_ref - y, nominal gain {} m/V, {}{}",
                                axis_label("servo", axis), g.kp, g.ki, g.kd, g.nominal_gain_m_per_V, notches_text(g),
                                g.enabled() ? "" : " (off: feedforward only)"));
  }
  lines.push_back(
      fmt::format("blocks: {} ticks per HX_SENSOR message ({:.4g} messages/s); commands taken up to {} s "
                  "ahead of the clock (bridge.max_lead_s)",
                  s.block_ticks, s.rate_hz / s.block_ticks, s.max_lead_s));
  lines.push_back(fmt::format("rt: {} tick(s) per wake-up, priority {}, I/O priority {}, lock_memory {}, cpu {}, {}",
                              s.rt.ticks_per_wake, s.rt.priority, s.rt.io_priority, s.rt.lock_memory, s.rt.cpu,
                              s.rt.required ? "required" : "not required"));
  return lines;
}

}  // namespace hystloop
