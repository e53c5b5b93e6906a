#include "ctl_requests.hpp"

#include <charconv>
#include <cmath>
#include <string>

#include <fstream>
#include <limits>
#include <sstream>
#include <utility>

#include "core/errors.hpp"
#include "hystloop/command_block_t.hpp"
#include "lcm/message_checks.hpp"
#include "lcm/trajectory_shape.hpp"
#include "loop/compensator.hpp"
#include "loop/feedback.hpp"
#include "loop/params_admission.hpp"
#include "models/mem.hpp"

namespace hystloop::ctl {

namespace {

std::int8_t shape_on_wire(std::string_view name) {
  if (const auto shape = trajectory_shape_named(name)) return to_wire(*shape);
  throw ParameterError("shape", "must be " + trajectory_shape_choices() + " (got '" + std::string(name) + "')");
}

}  // namespace

std::int64_t new_request_id(std::int64_t utime, int pid) noexcept {
  return (utime % 1'000'000'000'000'000) * 1000 + (pid % 1000) + 1;  // > 0, unique per us and pid
}

// The compensator's one table of mode names; FeedforwardMode is numbered as command_block_t::MODE_*.
std::int8_t parse_mode(std::string_view name) {
  return static_cast<std::int8_t>(parse_feedforward_mode(std::string(name), "mode"));
}

control_t make_control(std::int8_t command, std::string target, std::int64_t request_id, std::int64_t utime) {
  control_t msg{};
  msg.utime = utime;
  msg.request_id = request_id;
  msg.command = command;
  msg.target = std::move(target);
  return msg;
}

void GainsRequest::validate() const {
  // The servo's plausibility bounds at the default rig (10 kHz, the 1 kHz derivative filter), as
  // kMaxNotch_hz assumes it too; the bridge checks again at its own tick rate, with the gains
  // not given as they are in force there.
  FeedbackGains servo;
  const auto check = [](const char* name, const std::optional<double>& v, double& into) {
    if (!v) return;
    require_non_negative(name, *v);
    into = *v;
  };
  check("kp", kp, servo.kp);
  check("ki", ki, servo.ki);
  check("kd", kd, servo.kd);
  servo.check_bounds("");
  const auto check_notch = [](const char* hz_name, const char* q_name, const std::optional<double>& hz,
                              const std::optional<double>& q) {
    if (hz) require_in_range(hz_name, *hz, 0.0, kMaxNotch_hz);
    if (q) {
      if (hz && *hz == 0.0) throw ParameterError(q_name, std::string("only with a notch (--") + hz_name + " > 0)");
      require_in_range(q_name, *q, kNotchMinQ, kNotchMaxQ);
    }
  };
  check_notch("notch-hz", "notch-q", notch_hz, notch_q);
  check_notch("notch2-hz", "notch2-q", notch2_hz, notch2_q);
}

std::int8_t parse_learning(std::string_view name) {
  if (name == "on") return control_t::LEARNING_ON;
  if (name == "off") return control_t::LEARNING_OFF;
  if (name == "reset") return control_t::LEARNING_RESET;
  throw ParameterError("learning", "must be one of on|off|reset (got '" + std::string(name) + "')");
}

void parse_band(std::string_view band, ExperimentRequest& request) {
  const std::size_t colon = band.find(':');
  auto number = [&](std::string_view text) {
    double v = 0.0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (text.empty() || ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v) || v <= 0.0) {
      throw ParameterError("band", "expected F_MIN:F_MAX in Hz, both > 0 (got '" + std::string(band) + "')");
    }
    return v;
  };
  if (colon == std::string_view::npos) number({});
  const double lo = number(band.substr(0, colon));
  const double hi = number(band.substr(colon + 1));
  if (!(lo < hi)) throw ParameterError("band", "F_MIN must be below F_MAX (got '" + std::string(band) + "')");
  request.multisine.f_min_hz = lo;
  request.frequency_Hz = hi;
}

void ExperimentRequest::validate() const {
  if (kind.empty()) throw ParameterError("kind", "must not be empty");
  if (kind == "multisine") {
    if (!(multisine.f_min_hz > 0.0)) throw ParameterError("band", "a multisine needs its band (--band F_MIN:F_MAX)");
    // What the compensator will parse, checked here with the option names it maps to.
    try {
      make_experiment_spec(format_multisine_kind(multisine), amplitude_V, offset_V, frequency_Hz, duration_s);
    } catch (const ParameterError& e) {
      const std::string& f = e.field();
      const std::string option = f == "experiment.f_min" || f == "experiment.frequency_hz" ? "band"
                                 : f == "experiment.periods"                               ? "periods"
                                 : f == "experiment.realisations"                          ? "realisations"
                                 : f == "experiment.amplitude_V"                           ? "amplitude"
                                 : f == "experiment.duration_s"                            ? "period"
                                 : f == "experiment.offset_V"                              ? "offset"
                                                                                           : "kind";
      throw ParameterError(option, e.what());
    }
  } else if (kind != "sine" && kind != "settle") {
    throw ParameterError("kind", "must be sine, settle or multisine (got '" + kind + "')");
  }
  require_positive("amplitude", amplitude_V);
  require_in_range("amplitude", amplitude_V, 0.0, kMaxAbsVoltage_V);
  require_positive("frequency", frequency_Hz);
  require_in_range("frequency", frequency_Hz, 0.0, kMaxAbsFrequency_Hz);
  require_positive("duration", duration_s);
  require_in_range("duration", duration_s, 0.0, kMaxDuration_s);
  require_in_range("offset", offset_V, -kMaxAbsVoltage_V, kMaxAbsVoltage_V);
}

ServoGainsFigures GainsRequest::applied_to(ServoGainsFigures in_force) const noexcept {
  in_force.kp = kp.value_or(in_force.kp);
  in_force.ki_per_s = ki.value_or(in_force.ki_per_s);
  in_force.kd_s = kd.value_or(in_force.kd_s);
  in_force.notch_hz = notch_hz.value_or(in_force.notch_hz);
  in_force.notch_q = notch_q.value_or(in_force.notch_q);
  in_force.notch2_hz = notch2_hz.value_or(in_force.notch2_hz);
  in_force.notch2_q = notch2_q.value_or(in_force.notch2_q);
  return in_force;
}

ExperimentRequest sine_experiment(double offset_V, double amplitude_V, double frequency_Hz, double duration_s,
                                  std::string kind) {
  ExperimentRequest r;
  r.kind = std::move(kind);
  r.offset_V = offset_V;
  r.amplitude_V = amplitude_V;
  r.frequency_Hz = frequency_Hz;
  r.duration_s = duration_s;
  return r;
}

void apply(const GainsRequest& gains, control_t& msg) {
  gains.validate();
  const double keep = std::numeric_limits<double>::quiet_NaN();  // the bridge keeps that one
  msg.kp = gains.kp.value_or(keep);
  msg.ki = gains.ki.value_or(keep);
  msg.kd = gains.kd.value_or(keep);
  msg.notch_hz = gains.notch_hz.value_or(keep);
  msg.notch_q = gains.notch_q.value_or(keep);
  msg.notch2_hz = gains.notch2_hz.value_or(keep);
  msg.notch2_q = gains.notch2_q.value_or(keep);
  msg.axis = static_cast<std::int8_t>(gains.axis);
}

void apply(const ExperimentRequest& experiment, control_t& msg) {
  experiment.validate();
  msg.experiment = experiment.kind == "multisine" ? format_multisine_kind(experiment.multisine) : experiment.kind;
  msg.experiment_amplitude_V = experiment.amplitude_V;
  msg.experiment_frequency_Hz = experiment.frequency_Hz;
  msg.experiment_duration_s = experiment.duration_s;
  msg.experiment_offset_V = experiment.offset_V;
}

void TrajectoryRequest::validate() const {
  const std::int8_t s = shape_on_wire(shape);
  require_in_range("amplitude", amplitude_m, -kMaxAbsPosition_m, kMaxAbsPosition_m);
  require_in_range("offset", offset_m, -kMaxAbsPosition_m, kMaxAbsPosition_m);
  require_finite("phase", phase_rad);
  require_non_negative("blend", blend_s);
  if (s == trajectory_t::SINE || s == trajectory_t::COSINE || s == trajectory_t::TRIANGLE) {
    require_positive("frequency", frequency_Hz);
    require_in_range("frequency", frequency_Hz, 0.0, kMaxAbsFrequency_Hz);
  }
  if (s == trajectory_t::POINTS) {
    if (points_t_s.empty()) throw ParameterError("points-csv", "shape points needs at least one point (--points-csv)");
    if (points_t_s.size() > static_cast<std::size_t>(trajectory_t::MAX_POINTS)) {
      throw ParameterError("points-csv", "at most " + std::to_string(trajectory_t::MAX_POINTS) + " points (got " +
                                             std::to_string(points_t_s.size()) + ")");
    }
    for (std::size_t i = 0; i < points_t_s.size(); ++i) {
      require_non_negative("points-csv", points_t_s[i]);
      require_in_range("points-csv", points_y_m[i], -kMaxAbsPosition_m, kMaxAbsPosition_m);
      if (i > 0 && !(points_t_s[i] > points_t_s[i - 1])) {
        throw ParameterError("points-csv", "times must increase strictly (point " + std::to_string(i + 1) + ": " +
                                               number_text(points_t_s[i]) + " after " + number_text(points_t_s[i - 1]) +
                                               ")");
      }
    }
  } else if (!points_t_s.empty()) {
    throw ParameterError("points-csv", "only for --shape points");
  }
  require_non_negative("corner", corner_s);
  if (s == trajectory_t::TRIANGLE && !(corner_s < 0.5 / frequency_Hz)) {
    throw ParameterError("corner", "must be below half the period (" + number_text(0.5 / frequency_Hz) + " s at " +
                                       number_text(frequency_Hz) + " Hz; got " + number_text(corner_s) + " s)");
  }
  if (s != trajectory_t::TRIANGLE && corner_s != 0.0) throw ParameterError("corner", "only for --shape triangle");
}

TrajectoryRequest mem_paper_trajectory(double blend_s) {
  TrajectoryRequest r;
  r.shape = "cosine";
  r.amplitude_m = -1.6e-6;
  r.frequency_Hz = 1.0;
  r.blend_s = blend_s;
  return r;
}

void read_points_csv(const std::filesystem::path& file, TrajectoryRequest& request) {
  std::ifstream in(file);
  if (!in) throw ParameterError("points-csv", file.string() + ": cannot read");
  std::string line;
  int number = 0;
  request.points_t_s.clear();
  request.points_y_m.clear();
  while (std::getline(in, line)) {
    ++number;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    for (char& c : line) {
      if (c == ',' || c == ';' || c == '\t') c = ' ';
    }
    std::istringstream fields(line);
    double t = 0.0, y = 0.0;
    std::string rest;
    if (!(fields >> t >> y)) {
      if (request.points_t_s.empty() && number == 1) continue;  // a header line
      throw ParameterError("points-csv",
                           file.string() + " line " + std::to_string(number) + ": expected two numbers t_s,y_m");
    }
    if (fields >> rest) {
      throw ParameterError("points-csv", file.string() + " line " + std::to_string(number) +
                                             ": expected two columns t_s,y_m (got more)");
    }
    request.points_t_s.push_back(t);
    request.points_y_m.push_back(y);
  }
}

trajectory_t make_trajectory(const TrajectoryRequest& request, std::int64_t version, std::int64_t utime) {
  request.validate();
  trajectory_t msg{};
  msg.utime = utime;
  msg.version = version;
  msg.shape = shape_on_wire(request.shape);
  const bool periodic =
      msg.shape == trajectory_t::SINE || msg.shape == trajectory_t::COSINE || msg.shape == trajectory_t::TRIANGLE;
  msg.amplitude_m = request.amplitude_m;
  msg.offset_m = request.offset_m;
  msg.frequency_Hz = periodic ? request.frequency_Hz : 0.0;
  msg.phase_rad = request.phase_rad;
  msg.start_utime = 0;  // as soon as received
  msg.blend_s = request.blend_s;
  msg.n_points = static_cast<std::int32_t>(request.points_t_s.size());
  msg.points_t_s = request.points_t_s;
  msg.points_y_m = request.points_y_m;
  msg.corner_s = msg.shape == trajectory_t::TRIANGLE ? request.corner_s : 0.0;
  msg.if_infeasible = request.shape_to_feasible ? trajectory_t::SHAPE : trajectory_t::REFUSE;
  msg.axis = static_cast<std::int8_t>(request.axis);
  if (check_message(msg) != Verdict::kOk) throw ParameterError("trajectory", "refused by the message contract");
  return msg;
}

void ParamsRequest::validate() const {
  MemParams{c1, c2, c3}.validate();      // the MEM's own domain, naming c1, c2, c3
  require_in_range("c1", c1, 0.0, 1.0);  // and the contract's sanity bounds
  require_in_range("c3", c3, 0.0, 50.0);
  require_in_range("residual", residual_m, 0.0, kMaxAbsPosition_m);
  if (version < 1) throw ParameterError("version", "must be >= 1 (got " + std::to_string(version) + ")");
}

mem_params_t make_params(const ParamsRequest& request, std::int64_t utime) {
  request.validate();
  mem_params_t msg{};
  msg.utime = utime;
  msg.version = request.version;
  msg.publisher_id = process_publisher_id();  // each run is a new publisher: its version is never "stale"
  msg.c1 = request.c1;
  msg.c2 = request.c2;
  msg.c3 = request.c3;
  msg.residual_m = request.residual_m;
  msg.samples_used = 0;
  msg.window_s = 0.0;
  msg.valid = true;
  msg.source = "hystloop-ctl";
  msg.axis = static_cast<std::int8_t>(request.axis);
  if (check_message(msg) != Verdict::kOk) throw ParameterError("params", "refused by the message contract");
  return msg;
}

namespace {
void require_per_axis(const char* name, const std::vector<double>& v) {
  if (v.size() > 3) throw ParameterError(name, "takes at most one value per axis (x, y, z)");
}
}  // namespace

void ScanRequest::validate() const {
  if (path != "raster" && path != "lissajous") {
    throw ParameterError("path", "must be raster or lissajous (got '" + path + "')");
  }
  require_per_axis("centre", centre_m);
  require_in_range("blend", blend_s, 0.0, 60.0);
  if (path == "raster") {
    if (fast_axis == slow_axis) throw ParameterError("slow-axis", "must differ from --fast-axis");
    if (slow != "steps" && slow != "ramp") throw ParameterError("slow", "must be steps or ramp (got '" + slow + "')");
    require_in_range("lines", lines, 2, 4096);
    require_positive("width", width_m);
    require_non_negative("height", height_m);
    require_positive("line-rate", line_rate_Hz);
    require_non_negative("corner", corner_s);
    require_non_negative("settle", settle_s);
  } else {
    require_per_axis("amplitude", amplitude_m);
    require_per_axis("frequency", frequency_Hz);
    require_per_axis("phase", phase_rad);
    if (amplitude_m.empty()) throw ParameterError("amplitude", "give one amplitude per moving axis (x, y[, z]) [m]");
    if (frequency_Hz.size() != amplitude_m.size()) {
      throw ParameterError("frequency",
                           "give one frequency per amplitude (" + std::to_string(amplitude_m.size()) + ")");
    }
    require_positive("duration", duration_s);
  }
}

scan_t make_scan(const ScanRequest& request, std::int64_t version, std::int64_t utime) {
  request.validate();
  scan_t msg{};
  msg.utime = utime;
  msg.version = version;
  msg.path = request.path == "raster" ? scan_t::RASTER : scan_t::LISSAJOUS;
  for (std::size_t i = 0; i < request.centre_m.size(); ++i) msg.centre_m[i] = request.centre_m[i];
  msg.fast_axis = static_cast<std::int8_t>(request.fast_axis);
  msg.slow_axis = static_cast<std::int8_t>(request.slow_axis);
  msg.width_m = request.width_m;
  msg.height_m = request.height_m;
  msg.lines = request.lines;
  msg.line_rate_Hz = request.line_rate_Hz;
  msg.slow_mode = request.slow == "ramp" ? scan_t::RAMP : scan_t::STEPS;
  msg.corner_s = request.corner_s;
  msg.settle_s = request.settle_s;
  for (std::size_t i = 0; i < request.amplitude_m.size(); ++i) msg.amplitude_m[i] = request.amplitude_m[i];
  for (std::size_t i = 0; i < request.frequency_Hz.size(); ++i) msg.frequency_Hz[i] = request.frequency_Hz[i];
  for (std::size_t i = 0; i < request.phase_rad.size(); ++i) msg.phase_rad[i] = request.phase_rad[i];
  msg.duration_s = request.duration_s;
  msg.decouple = request.decouple ? 1 : 0;
  msg.start_utime = 0;
  msg.blend_s = request.blend_s;
  if (check_message(msg) != Verdict::kOk) throw ParameterError("scan", "refused by the message contract");
  return msg;
}

}  // namespace hystloop::ctl
