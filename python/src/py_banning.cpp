// hystloop.identify_banning: hystloop-identify --model banning on the logs of a sine series
// (hystloop-ctl experiment --banning-series): the same experiment splitter (identify_core's
// read_logged_experiments), the same fit (ident's fit_banning), the same report lines and YAML
// (tools/identify/identify_run.cpp's fit_banning_logs and fit_banning_and_emit), the same refusals.
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "ident/banning_fit.hpp"
#include "ident/params_yaml.hpp"
#include "lcm/channels.hpp"
#include "log_experiments.hpp"
#include "log_samples.hpp"
#include "models/axis_coupling.hpp"
#include "py_common.hpp"

namespace hystloop::python {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct BanningResult {
  std::string status = "ok", reason;
  double a = kNaN, b = kNaN, alpha = kNaN, s_max = kNaN, k = kNaN, c = kNaN;
  bool stage_identified = false;
  std::string stage_note;  // why the stage was not identified ('' when it was)
  double centre_rms_m = kNaN, slope_rel_rms = kNaN, area_rel_rms = kNaN, magnitude_rel_rms = kNaN;
  bool lag_identified = false;
  double delay_s = kNaN, lag_phase_rms_rad = kNaN, solve_time_s = kNaN;
  std::size_t lag_experiments = 0, experiments_fitted = 0;
  std::string lag_note;
  py::list points;          // one dict per experiment fitted, as the report's table
  std::string experiments;  // the tool's list of the experiments the log holds
  std::string report;       // the tool's lines of the fit (table, Banning, fit, lag)
  std::string yaml;         // the snippet the tool prints and writes ('' without a fit)
  bool ok() const { return status == "ok"; }
};

// printf into a std::string, as the tool prints to stdout.
[[gnu::format(printf, 2, 3)]] void append(std::string& out, const char* format, ...) {
  std::va_list args;
  va_start(args, format);
  std::va_list copy;
  va_copy(copy, args);
  const int n = std::vsnprintf(nullptr, 0, format, copy);
  va_end(copy);
  if (n > 0) {
    std::string chunk(static_cast<std::size_t>(n) + 1, '\0');
    std::vsnprintf(chunk.data(), chunk.size(), format, args);
    chunk.resize(static_cast<std::size_t>(n));
    out += chunk;
  }
  va_end(args);
}

py::dict point_dict(const BanningPoint& p) {
  py::dict d;
  d["offset_V"] = p.offset_V;
  d["amplitude_V"] = p.amplitude_V;
  d["frequency_Hz"] = p.frequency_Hz;
  d["kind"] = p.magnitude_experiment ? "magnitude" : "loop";
  d["used"] = p.used;
  d["note"] = p.note;
  d["area_fitted"] = p.area_fitted;
  if (p.magnitude_experiment) {
    d["magnitude"] = p.magnitude;
    d["response_m"] = p.response_m;
    d["phase_lag_rad"] = p.phase_lag_rad;
  } else {
    d["y_centre_m"] = p.features.y_centre;
    d["slope_m_per_V"] = p.features.slope;
    d["area_m_V"] = p.features.area;
    d["lag_rad"] = p.lag_rad;
    d["lag_area_m_V"] = p.lag_area;
  }
  return d;
}

// fit_banning_and_emit's report, line for line.
void take_fit(const BanningFitResult& r, BanningResult& out) {
  std::string& s = out.report;
  append(s, "experiment  offset [V]  amplitude [V]  frequency [Hz]  kind       feature\n");
  for (std::size_t i = 0; i < r.points.size(); ++i) {
    const auto& p = r.points[i];
    out.points.append(point_dict(p));
    if (!p.used) {
      append(s, "%10zu  skipped: %s\n", i, p.note.c_str());
      continue;
    }
    append(s, "%10zu  %10.3f  %13.3f  %14.3f  ", i, p.offset_V, p.amplitude_V, p.frequency_Hz);
    if (p.magnitude_experiment && r.stage_identified) {
      append(s, "magnitude  h = %.5g", p.magnitude);
    } else if (p.magnitude_experiment) {
      append(s, "magnitude  y1 = %.5g nm", p.response_m * 1e9);
    } else {
      append(s, "loop       centre %.5g nm, slope %.5g nm/V, area %.5g nm V", p.features.y_centre * 1e9,
             p.features.slope * 1e9, p.features.area * 1e9);
      if (p.area_fitted && p.lag_area != 0.0) append(s, " %+.3g for the lag", p.lag_area * 1e9);
    }
    append(s, "\n");
  }
  out.experiments_fitted = r.points.size();
  if (!r.ok()) {
    out.status = std::string(to_string(r.status));
    out.reason = r.reason;
    return;
  }
  out.a = r.hysteresis.a, out.b = r.hysteresis.b, out.alpha = r.hysteresis.alpha, out.s_max = r.hysteresis.s_max;
  out.stage_identified = r.stage_identified;
  append(s, "Banning: a = %.6g m/V, b = %.6g m/V, alpha = %.6g 1/V\n", r.hysteresis.a, r.hysteresis.b,
         r.hysteresis.alpha);
  if (r.stage_identified) {
    out.k = r.stage.k, out.c = r.stage.c;
    append(s, "         k = %.6g 1/s^2, c = %.6g 1/s (f_n = %.1f Hz, zeta = %.4f)\n", r.stage.k, r.stage.c,
           r.stage.natural_frequency() / (2.0 * 3.141592653589793), r.stage.damping_ratio());
  } else {
    out.stage_note = r.reason;
    append(s, "         stage not identified: %s\n", r.reason.c_str());
  }
  out.centre_rms_m = r.centre_rms_m, out.slope_rel_rms = r.slope_rel_rms, out.area_rel_rms = r.area_rel_rms;
  out.magnitude_rel_rms = r.magnitude_rel_rms, out.solve_time_s = r.solve_time_s;
  append(s, "fit: centre line %.4g nm RMS, slopes %.3g %% RMS, areas %.3g %% RMS, magnitudes %.3g %% RMS, %.1f ms\n",
         r.centre_rms_m * 1e9, r.slope_rel_rms * 100.0, r.area_rel_rms * 100.0, r.magnitude_rel_rms * 100.0,
         r.solve_time_s * 1e3);
  out.lag_identified = r.lag_identified;
  out.lag_note = r.lag_note;
  if (r.lag_identified) {
    out.delay_s = r.delay_s, out.lag_phase_rms_rad = r.lag_phase_rms_rad, out.lag_experiments = r.lag_experiments;
    double lo = 1e300, hi = -1e300;
    for (const auto& p : r.points) {
      if (!p.area_fitted || !(p.features.area > 0.0)) continue;
      lo = std::min(lo, p.lag_area / p.features.area), hi = std::max(hi, p.lag_area / p.features.area);
    }
    append(s,
           "lag: %.3g us beyond the stage model (phases of %zu magnitude experiments below f_n/2, %.2g mrad RMS); "
           "the areas alpha is fitted to corrected by %+.2g .. %+.2g %%\n",
           r.delay_s * 1e6, r.lag_experiments, r.lag_phase_rms_rad * 1e3, lo * 100.0, hi * 100.0);
  } else if (!r.lag_note.empty()) {
    append(s, "lag: %s\n", r.lag_note.c_str());
  }
  out.yaml = to_yaml(r.hysteresis, r.stage_identified ? &r.stage : nullptr);
}

std::vector<std::string> paths_of(const py::object& logs) {
  const py::module_ os = py::module_::import("os");
  std::vector<std::string> paths;
  if (py::isinstance<py::str>(logs) || py::hasattr(logs, "__fspath__")) {
    paths.push_back(os.attr("fspath")(logs).cast<std::string>());
  } else {
    for (const py::handle p : logs) paths.push_back(os.attr("fspath")(p).cast<std::string>());
  }
  if (paths.empty()) throw PyParameterError("logs", "no log file given");
  return paths;
}

void check_fraction(double v, const char* field) {
  if (!(v >= 0.0 && v <= 1.0))
    throw PyParameterError(field, std::string(field) + ": " + number_text(v, 6) + " is not in [0, 1]");
}

BanningResult identify_banning(const py::object& logs, const std::string& rig, const std::string& compensator,
                               double dt_s, int axis, double max_late, double max_missing, bool check) {
  const std::vector<std::string> files = paths_of(logs);
  if (axis < 0 || axis >= kMaxAxes)
    throw PyParameterError("axis", "axis: " + std::to_string(axis) + " is not 0 (x), 1 (y) or 2 (z)");
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) throw PyParameterError("dt_s", "dt_s: must be a finite number > 0");
  check_fraction(max_late, "max_late");
  check_fraction(max_missing, "max_missing");
  // As identify_run.cpp's experiment_options.
  ExperimentLogOptions o;
  try {
    o.control_channel = channel_name(rig, kControlSuffix);
    o.command_channel = channel_name(rig, kCommandSuffix);
    o.sensor_channel = channel_name(rig, kSensorSuffix);
  } catch (const ParameterError& e) {
    throw PyParameterError("rig", std::string("rig: ") + e.what());
  }
  o.compensator_process = compensator;
  o.dt_s = dt_s;
  o.max_not_as_commanded = max_late;
  o.max_missing = max_missing;
  o.rate_independent_below_Hz = BanningFitOptions{}.frequency_threshold_Hz;
  o.axis = axis;

  BanningResult out;
  {
    LoggedExperiments logged;
    BanningFitResult r;
    bool any = false;
    {
      const py::gil_scoped_release unlocked;
      try {
        logged = read_logged_experiments(files, o);
      } catch (const SampleLogError& e) {  // PyParameterError holds no Python object: thrown unlocked
        throw PyParameterError("logs", e.what());
      } catch (const ParameterError& e) {
        throw PyParameterError(e.field(), e.what());
      }
      std::vector<BanningExperimentData> data;
      for (const auto& e : logged.experiments) {
        if (!e.spec.settle && e.usable()) data.push_back({e.samples.u, e.samples.y, 1.0 / dt_s, e.spec.frequency_hz});
      }
      any = !data.empty();
      if (any) r = fit_banning(data);
    }
    out.experiments = describe(logged);
    if (!any) {
      out.status = std::string(to_string(FitStatus::too_few_samples));
      out.reason = "no usable measured experiment in the log (see the list above)";
    } else {
      take_fit(r, out);
    }
  }
  if (check && !out.ok()) throw PyFitError(out.status, out.reason, py::cast(out));
  return out;
}

std::string repr(const BanningResult& r) {
  if (!r.ok()) return "hystloop.BanningResult(no fit (" + r.status + "): " + r.reason + ")";
  std::string s = "hystloop.BanningResult(a " + number_text(r.a, 6) + " m/V, b " + number_text(r.b, 6) +
                  " m/V, alpha " + number_text(r.alpha, 6) + " 1/V";
  if (r.stage_identified) s += ", k " + number_text(r.k, 6) + " 1/s^2, c " + number_text(r.c, 6) + " 1/s";
  return s + ", " + std::to_string(r.experiments_fitted) + " experiments)";
}

}  // namespace

void register_banning(py::module_& m) {
  py::class_<BanningResult>(m, "BanningResult", "what hystloop.identify_banning found (hystloop-identify's output)")
      .def_readonly("status", &BanningResult::status, "ok, or the fit's refusal (FitStatus: too_few_samples, ...)")
      .def_readonly("reason", &BanningResult::reason, "why there is no fit ('' when ok)")
      .def_property_readonly("ok", &BanningResult::ok, "status == 'ok'")
      .def_readonly("a", &BanningResult::a, "Coleman-Hodgdon a [m/V] (NaN without a fit)")
      .def_readonly("b", &BanningResult::b, "Coleman-Hodgdon b [m/V]")
      .def_readonly("alpha", &BanningResult::alpha, "Coleman-Hodgdon alpha [1/V]")
      .def_readonly("s_max", &BanningResult::s_max, "saturation [V] (not fitted: the default, as in the YAML)")
      .def_readonly("k", &BanningResult::k, "stage k [1/s^2] (NaN when the stage was not identified)")
      .def_readonly("c", &BanningResult::c, "stage c [1/s] (NaN when the stage was not identified)")
      .def_readonly("stage_identified", &BanningResult::stage_identified, "k and c were identified")
      .def_readonly("stage_note", &BanningResult::stage_note, "why the stage was not identified ('' when it was)")
      .def_property_readonly(
          "params",
          [](const BanningResult& r) {
            py::dict d;
            if (!r.ok()) return d;
            py::dict h;
            h["a"] = r.a, h["b"] = r.b, h["alpha"] = r.alpha, h["s_max"] = r.s_max;
            d["hysteresis"] = h;
            if (r.stage_identified) {
              py::dict st;
              st["k"] = r.k, st["c"] = r.c;
              d["stage"] = st;
            }
            return d;
          },
          "the parameters as the YAML's banning section holds them: {'hysteresis': {a, b, alpha, s_max}, "
          "'stage': {k, c}} (SI; no 'stage' when it was not identified)")
      .def_readonly("centre_rms_m", &BanningResult::centre_rms_m, "centre line fit residual [m RMS]")
      .def_readonly("slope_rel_rms", &BanningResult::slope_rel_rms, "slopes' relative residual [-, RMS]")
      .def_readonly("area_rel_rms", &BanningResult::area_rel_rms, "areas' relative residual [-, RMS]")
      .def_readonly("magnitude_rel_rms", &BanningResult::magnitude_rel_rms, "magnitudes' relative residual [-, RMS]")
      .def_readonly("lag_identified", &BanningResult::lag_identified, "the loop areas were corrected for the lag")
      .def_readonly("delay_s", &BanningResult::delay_s, "the lag beyond the stage model as a delay [s]")
      .def_readonly("lag_phase_rms_rad", &BanningResult::lag_phase_rms_rad, "residual of the phase fit [rad RMS]")
      .def_readonly("lag_experiments", &BanningResult::lag_experiments, "magnitude experiments the lag came from")
      .def_readonly("lag_note", &BanningResult::lag_note, "why the lag was not corrected ('' when it was)")
      .def_readonly("solve_time_s", &BanningResult::solve_time_s, "the solver's time [s]")
      .def_readonly("points", &BanningResult::points,
                    "one dict per experiment fitted, as the report's table (offset_V, amplitude_V, frequency_Hz, "
                    "kind, used, note, and the loop's or the magnitude experiment's features)")
      .def_readonly("experiments", &BanningResult::experiments, "the tool's list of the experiments in the log")
      .def_readonly("report", &BanningResult::report, "the tool's lines of the fit (table, Banning, fit, lag)")
      .def_readonly("yaml", &BanningResult::yaml, "the YAML snippet hystloop-identify prints and writes ('' if none)")
      .def(
          "to_yaml",
          [](const BanningResult& r, const std::string& path) {
            if (!r.ok()) throw py::value_error("no fit (" + r.status + "): " + r.reason);
            const py::object f = py::module_::import("builtins").attr("open")(path, "w");
            f.attr("write")("# written by hystloop-identify\n" + r.yaml);
            f.attr("close")();
          },
          py::arg("path"), "writes the snippet as hystloop-identify --out does")
      .def("__repr__", &repr);

  m.def("identify_banning", &identify_banning, py::arg("logs"), py::kw_only(),
        py::arg("rig") = std::string(kDefaultRigPrefix), py::arg("compensator") = "compensator", py::arg("dt_s") = 1e-4,
        py::arg("axis") = 0, py::arg("max_late") = 0.02, py::arg("max_missing") = 0.01, py::arg("check") = true,
        R"doc(identify_banning(logs, *, rig="HX_", compensator="compensator", dt_s=1e-4, axis=0, max_late=0.02,
                 max_missing=0.01, check=True) -> BanningResult

Banning's model (Coleman-Hodgdon hysteresis + second-order stage) from the LCM log(s) of a sine
series the live loop ran (hystloop-ctl experiment --banning-series), as
hystloop-identify --model banning LOG... does (same code, same numbers to the last bit):
  logs          a log file or a list of them, read in order as one record
  rig           channel prefix: <rig>CONTROL requests, <rig>COMMAND and <rig>SENSOR blocks
  compensator   process name whose experiment requests count
  dt_s          the rig's tick [s]
  axis          0 x, 1 y, 2 z
  max_late      fraction of a frequency-response experiment's samples that may be LATE_COMMAND,
                SATURATED or SLEW_LIMITED (--max-late)
  max_missing   fraction of a hysteresis-loop experiment's ticks that may lack a sample (--max-missing)
  check         True: no fit raises hystloop.FitError ("no fit (status): reason", with .result);
                False: the result says so (status, reason)
A log that cannot be read or holds no experiment, or an option out of range, raises
hystloop.ParameterError.)doc");
}

}  // namespace hystloop::python
