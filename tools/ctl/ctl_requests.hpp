#pragma once
// What hystloop-ctl sends, built and validated without any I/O: each request type checks
// its values where they enter (ParameterError naming the option, e.g. "c1: must be > 0
// (got -1)") and converts to the LCM message, which must then also pass the contract's
// check_message.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hystloop/control_t.hpp"
#include "hystloop/mem_params_t.hpp"
#include "hystloop/scan_t.hpp"
#include "hystloop/trajectory_t.hpp"
#include "lcm/servo_gains_status.hpp"
#include "loop/experiment.hpp"

namespace hystloop::ctl {

// A request id unique per sender and request (> 0): wall time [us] and the pid.
std::int64_t new_request_id(std::int64_t utime, int pid) noexcept;

// "off"|"linear"|"mem"|"pi"|"katalenic" -> command_block_t::MODE_*; throws ParameterError("mode").
std::int8_t parse_mode(std::string_view name);

// A control_t with the common fields set and every other field neutral (0 / empty).
control_t make_control(std::int8_t command, std::string target, std::int64_t request_id, std::int64_t utime);

struct GainsRequest {
  // Each gain the request changes; one not given stays as in force (sent as NaN).
  std::optional<double> kp;  // [-]
  std::optional<double> ki;  // [1/s]
  std::optional<double> kd;  // [s]
  // The servo's notch at the stage's resonance: centre [Hz], 0 = remove it, else in
  // (0, kMaxNotch_hz]; and its quality factor, in [kNotchMinQ, kNotchMaxQ] (loop/feedback.hpp).
  std::optional<double> notch_hz;
  std::optional<double> notch_q;
  // A second notch in cascade (a second mode of the stage), the same way.
  std::optional<double> notch2_hz{};
  std::optional<double> notch2_q{};
  // The axis whose servo it sets (0 x, 1 y, 2 z), or every axis's (control_t::EVERY_AXIS): each
  // axis then keeps its own value of what is not given.
  int axis = -1;
  static constexpr double kMaxNotch_hz = 4500.0;  // below half the 10 kHz tick rate
  // Nothing given: the request is a question (print the gains in force).
  bool empty() const noexcept { return !kp && !ki && !kd && !notch_hz && !notch_q && !notch2_hz && !notch2_q; }
  // The gains in force with those this request changes.
  ServoGainsFigures applied_to(ServoGainsFigures in_force) const noexcept;
  // Given gains finite, >= 0 and within the servo's plausibility bounds at 10 kHz (kp <= 2, ki <= 1e4 1/s,
  // kd <= 5.2e-4 s: loop/feedback.hpp); the notches as above ("notch-hz", "notch2-q").
  void validate() const;
};

struct ExperimentRequest {
  std::string kind = "sine";        // sine | settle | multisine; control_t.experiment
  double amplitude_V = 0.0;         // > 0 (a multisine's rms, or peak with multisine.peak)
  double frequency_Hz = 0.0;        // > 0 (a multisine's f_max)
  double duration_s = 0.0;          // > 0 (a multisine's period: its frequency resolution is 1 / it)
  double offset_V = 0.0;            // finite
  MultisineExperiment multisine{};  // kind multisine: f_min and the rest (loop/experiment.hpp)
  void validate() const;
};

// A sine experiment (or a settle: the same sine, marked for identification to skip).
ExperimentRequest sine_experiment(double offset_V, double amplitude_V, double frequency_Hz, double duration_s,
                                  std::string kind = "sine");

// --band F_MIN:F_MAX [Hz] of a multisine: sets request.multisine.f_min_hz and request.frequency_Hz.
// Throws ParameterError("band").
void parse_band(std::string_view band, ExperimentRequest& request);

// "on"|"off"|"reset" -> control_t::LEARNING_*; throws ParameterError("learning").
std::int8_t parse_learning(std::string_view name);

void apply(const GainsRequest& gains, control_t& msg);
void apply(const ExperimentRequest& experiment, control_t& msg);

struct TrajectoryRequest {
  std::string shape;  // cosine|sine|triangle|hold|points
  double amplitude_m = 0.0;
  double frequency_Hz = 1.0;  // > 0 for the periodic shapes
  double offset_m = 0.0;
  double phase_rad = 0.0;
  double blend_s = 1.0;                        // fade-in from the previous reference, >= 0
  std::vector<double> points_t_s, points_y_m;  // points: >= 1, t >= 0 strictly increasing
  double corner_s = 0.0;  // triangle only: each corner's duration, below half the period; 0 = the compensator's choice
  bool shape_to_feasible = false;  // if_infeasible SHAPE (else REFUSE)
  int axis = 0;                    // the axis it moves (0: x)
  void validate() const;
};

// The MEM paper's reference, eq. (24): y_d(t) = -1.6 um * cos(2 pi t).
TrajectoryRequest mem_paper_trajectory(double blend_s);

// Reads "t_s,y_m" rows (a header line and '#' comments are skipped) into the request.
// Throws ParameterError("points-csv", "<file> line N: ...").
void read_points_csv(const std::filesystem::path& file, TrajectoryRequest& request);

// version: increases per new trajectory (ctl uses the wall time in us); start "as received".
trajectory_t make_trajectory(const TrajectoryRequest& request, std::int64_t version, std::int64_t utime);

struct ParamsRequest {
  double c1 = 0.0;           // [m/V], > 0 (and <= 1, the contract's sanity bound)
  double c2 = 0.0;           // [m/V^(1+c3)], >= 0
  double c3 = 0.0;           // [-], 0 < c3 <= 50
  double residual_m = 0.0;   // >= 0
  std::int32_t version = 0;  // >= 1
  int axis = 0;              // the axis whose hysteresis it models (0: x)
  void validate() const;
};

// valid = true, source "hystloop-ctl".
mem_params_t make_params(const ParamsRequest& request, std::int64_t utime);

// A path of every axis (HX_SCAN): a raster or a Lissajous figure (scan_t has the geometry).
struct ScanRequest {
  std::string path;  // raster | lissajous
  // raster
  int fast_axis = 0;
  int slow_axis = 1;
  double width_m = 1e-6;   // fast-axis travel, peak to peak, > 0
  double height_m = 1e-6;  // slow-axis travel, first line to last, >= 0
  int lines = 64;          // 2..4096
  double line_rate_Hz = 50.0;
  std::string slow = "steps";  // steps | ramp
  double corner_s = 0.0;       // 0: the compensator's choice
  double settle_s = 0.05;
  // lissajous: per axis (x, y[, z])
  std::vector<double> amplitude_m, frequency_Hz, phase_rad;
  double duration_s = 1.0;
  std::vector<double> centre_m;  // per axis, default 0
  bool decouple = true;
  double blend_s = 0.3;   // the approach: gentle enough that learning has room on the path (scan.yaml's too)
  void validate() const;  // throws ParameterError naming the option
};

// version as make_trajectory's; start as soon as the approach allows.
scan_t make_scan(const ScanRequest& request, std::int64_t version, std::int64_t utime);

}  // namespace hystloop::ctl
