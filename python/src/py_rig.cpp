// hystloop.Rig: a running rig from Python, through hystloop-ctl's own client (tools/ctl
// rig_client.hpp): the same URL safety (ttl 0 unless allow_network), the same signed and
// acknowledged requests, RigError with hystloop-ctl's reason when a request is not confirmed.
// Every wait releases the GIL and ends within its timeout.
#include <pybind11/stl.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <optional>
#include <string>
#include <utility>

#include "core/config.hpp"
#include "core/errors.hpp"
#include "py_common.hpp"
#include "rig_client.hpp"

namespace hystloop::python {

namespace {

// Runs f without the GIL; the product's refusals become Python's (ParameterError names the field).
template <class F>
auto unlocked(F&& f) {
  try {
    const py::gil_scoped_release release;
    return f();
  } catch (const ParameterError& e) {
    throw PyParameterError(e.field(), e.what());
  }
}

py::array_t<double> doubles(const std::vector<double>& v) {
  py::array_t<double> a = new_array(v.size());
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

template <class T>
py::array_t<T> integers(const std::vector<T>& v) {
  py::array_t<T> a(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

// A recording as a dict of numpy arrays (one row per tick and axis) with its figures.
py::dict ticks_dict(const ctl::RecordedTicks& r) {
  py::dict d;
  d["seq"] = integers(r.seq);
  d["axis"] = integers(r.axis);
  d["t_s"] = [&] {
    py::array_t<double> t = new_array(r.seq.size());
    for (std::size_t i = 0; i < r.seq.size(); ++i) t.mutable_data()[i] = static_cast<double>(r.seq[i]) * r.dt_s;
    return t;
  }();
  d["u_V"] = doubles(r.u_V);
  d["u_ff_V"] = doubles(r.u_ff_V);
  d["u_fb_V"] = doubles(r.u_fb_V);
  d["y_ref_m"] = doubles(r.y_ref_m);
  d["y_m"] = doubles(r.y_m);
  d["y_true_m"] = doubles(r.y_true_m);
  d["flags"] = integers(r.flags);
  d["axes"] = r.axes;
  d["dt_s"] = r.dt_s;
  d["missing_ticks"] = r.missing_ticks;
  d["blocks"] = r.blocks;
  return d;
}

}  // namespace

void register_rig(py::module_& m) {
  py::register_exception<ctl::RigError>(m, "RigError", PyExc_RuntimeError);

  py::class_<ctl::RigClient>(m, "Rig", R"(A running hystloop rig over LCM, as hystloop-ctl operates it.

Rig(url=None, rig=None, allow_network=False, key_file=None, timeout=3.0,
    bridge="bridge", compensator="compensator")

url: the LCM URL (None: $LCM_DEFAULT_URL, else udpm with ttl=0: this host only); a URL that
  reaches other hosts needs allow_network=True. rig: the channel prefix (None: $HYSTLOOP_RIG,
  else "HX_"). key_file: the rig key (auth.key_file of the services) to sign requests with on a
  keyed rig (None: $HYSTLOOP_KEY_FILE, else unsigned). `deploy/hystloop python SCRIPT` sets the
  three for its rig. timeout [s]: how long
  each acknowledged request waits for its answers. Every request returns when the processes it
  is for confirmed it, and raises RigError with their answers otherwise (refused, no answer, no
  rig running); bad values raise ParameterError before anything is sent.)")
      .def(py::init([](const std::optional<std::string>& url, const std::optional<std::string>& rig, bool allow_network,
                       const std::optional<std::string>& key_file, double timeout, std::string bridge,
                       std::string compensator) {
             // Not given: from the environment deploy/hystloop python sets for its rig.
             const auto env = [](const char* name, const char* fallback) {
               const char* v = std::getenv(name);  // NOLINT(concurrency-mt-unsafe): read once, at construction
               return std::string(v != nullptr && *v != '\0' ? v : fallback);
             };
             ctl::RigClientOptions o;
             o.link.lcm_url = url.value_or("");
             o.link.rig = rig.value_or(env("HYSTLOOP_RIG", "HX_"));
             o.link.allow_network = allow_network;
             o.key_file = key_file.value_or(env("HYSTLOOP_KEY_FILE", ""));
             o.timeout_s = timeout;
             o.bridge = std::move(bridge);
             o.compensator = std::move(compensator);
             return unlocked([&] { return std::make_unique<ctl::RigClient>(o); });
           }),
           py::arg("url") = py::none(), py::arg("rig") = py::none(), py::arg("allow_network") = false,
           py::arg("key_file") = py::none(), py::arg("timeout") = 3.0, py::arg("bridge") = "bridge",
           py::arg("compensator") = "compensator")
      .def_static(
          "from_rig_file",
          [](const std::string& path, bool allow_network, const std::optional<std::string>& key_file, double timeout) {
            // What deploy/hystloop --host reads from it: rig.prefix, rig.lcm_url with rig.ttl, rig.key_file.
            ctl::RigClientOptions o;
            try {
              const Config rig_file = Config::load_file(path);
              o.link.rig = rig_file.get<std::string>("rig.prefix", "HX_");
              const std::string url = rig_file.get<std::string>("rig.lcm_url");
              const auto ttl = rig_file.get_int_in_range("rig.ttl", 0, 0, 1);
              if (url.find("ttl=") != std::string::npos) {
                rig_file.fail("rig.lcm_url", "a URL without ttl (give it as rig.ttl), got '" + url + "'");
              }
              o.link.lcm_url = url + (url.find('?') == std::string::npos ? "?" : "&") + "ttl=" + std::to_string(ttl);
              o.key_file = key_file.value_or(rig_file.get<std::string>("rig.key_file", ""));
            } catch (const ConfigError& e) {
              throw PyParameterError(e.field(), e.what());
            }
            o.link.allow_network = allow_network;
            o.timeout_s = timeout;
            return unlocked([&] { return std::make_unique<ctl::RigClient>(o); });
          },
          py::arg("path"), py::arg("allow_network") = false, py::arg("key_file") = py::none(), py::arg("timeout") = 3.0,
          R"(The rig a rig file describes (deploy/rig.yaml: rig.prefix, rig.lcm_url with rig.ttl, rig.key_file,
a relative key path taken from the current directory). A rig over the lab's network (ttl 1)
needs allow_network=True, as hystloop-ctl's --allow-network.)")
      .def_property_readonly("url", &ctl::RigClient::url, "The LCM URL in use")
      .def(
          "status",
          [](ctl::RigClient& rig, double listen) {
            const auto reports = unlocked([&] { return rig.status(listen); });
            py::dict out;
            for (const ctl::ProcessReport& r : reports) {
              py::dict counters;
              for (const auto& [name, value] : r.counters) counters[py::str(name)] = value;
              py::dict p;
              p["state"] = r.state;
              p["detail"] = r.detail;
              p["host"] = r.host;
              p["utime_us"] = r.utime;
              p["late"] = r.late;
              p["rejected"] = r.rejected;
              p["counters"] = counters;
              out[py::str(r.process)] = p;
            }
            return out;
          },
          py::arg("listen") = 1.5,
          R"(The latest HX_STATUS report of every process heard within `listen` seconds: {process: {state,
detail, host, utime_us, late, rejected, counters}}. Empty when no rig is running.)")
      .def(
          "arm", [](ctl::RigClient& rig) { unlocked([&] { rig.arm(); }); },
          "Bridge: leave the safe state (confirmed when its report shows armed = 1).")
      .def(
          "disarm", [](ctl::RigClient& rig) { unlocked([&] { rig.disarm(); }); },
          "Bridge: enter the safe state now (confirmed when its report shows armed = 0).")
      .def(
          "set_gains",
          [](ctl::RigClient& rig, std::optional<double> kp, std::optional<double> ki, std::optional<double> kd,
             std::optional<double> notch_hz, std::optional<double> notch_q, std::optional<int> axis,
             std::optional<double> notch2_hz, std::optional<double> notch2_q) {
            ctl::GainsRequest g;
            g.kp = kp;
            g.ki = ki;
            g.kd = kd;
            g.notch_hz = notch_hz;
            g.notch_q = notch_q;
            g.notch2_hz = notch2_hz;
            g.notch2_q = notch2_q;
            g.axis = axis.value_or(-1);
            unlocked([&] { rig.set_gains(g); });
          },
          py::arg("kp") = py::none(), py::arg("ki") = py::none(), py::arg("kd") = py::none(),
          py::arg("notch_hz") = py::none(), py::arg("notch_q") = py::none(), py::arg("axis") = py::none(),
          py::arg("notch2_hz") = py::none(), py::arg("notch2_q") = py::none(),
          R"(Bridge: the servo's gains, bumplessly; a gain not given stays as in force. kp [-], ki [1/s],
kd [s], notch_hz [Hz] (0 removes the notch), notch_q [-]; notch2_hz, notch2_q a second notch in
cascade (a second mode of the stage). axis: 0 x, 1 y, 2 z; None: every axis.)")
      .def(
          "set_mode", [](ctl::RigClient& rig, const std::string& mode) { unlocked([&] { rig.set_mode(mode); }); },
          py::arg("mode"), "Compensator: the feedforward mode (off, linear, mem, ...), confirmed by its report.")
      .def(
          "learn", [](ctl::RigClient& rig, const std::string& what) { unlocked([&] { rig.learn(what); }); },
          py::arg("what"), "Compensator: learning for periodic references: 'on', 'off' or 'reset'.")
      .def(
          "experiment",
          [](ctl::RigClient& rig, double amplitude_V, double frequency_Hz, double duration_s, double offset_V,
             std::string kind, int axis) {
            ctl::ExperimentRequest e;
            e.kind = std::move(kind);
            e.amplitude_V = amplitude_V;
            e.frequency_Hz = frequency_Hz;
            e.duration_s = duration_s;
            e.offset_V = offset_V;
            unlocked([&] { rig.experiment(e, axis); });
          },
          py::arg("amplitude_V"), py::arg("frequency_Hz"), py::arg("duration_s"), py::arg("offset_V") = 0.0,
          py::arg("kind") = "sine", py::arg("axis") = 0,
          R"(Compensator: an identification experiment on `axis` (0 x): a sine of amplitude_V [V] about
offset_V [V] at frequency_Hz [Hz] for duration_s [s] (whole periods); kind 'sine' or 'settle'.
Returns when the compensator took it; record() its samples.)")
      .def(
          "stop_experiment", [](ctl::RigClient& rig) { unlocked([&] { rig.stop_experiment(); }); },
          "Compensator: stop the experiment running and drop the queued ones.")
      .def(
          "set_trajectory",
          [](ctl::RigClient& rig, std::string shape, double amplitude_m, double frequency_Hz, double offset_m,
             double phase_rad, double blend_s, double corner_s, bool shape_if_infeasible, int axis,
             std::optional<InArray> t_s, std::optional<InArray> y_m) {
            ctl::TrajectoryRequest r;
            r.shape = std::move(shape);
            r.amplitude_m = amplitude_m;
            r.frequency_Hz = frequency_Hz;
            r.offset_m = offset_m;
            r.phase_rad = phase_rad;
            r.blend_s = blend_s;
            r.corner_s = corner_s;
            r.shape_to_feasible = shape_if_infeasible;
            r.axis = axis;
            if (t_s.has_value() != y_m.has_value())
              throw PyParameterError("points", "give both t_s and y_m, or neither");
            if (t_s) {
              const std::span<const double> t = view_1d(*t_s, "t_s");
              const std::span<const double> y = view_1d(*y_m, "y_m");
              r.points_t_s.assign(t.begin(), t.end());
              r.points_y_m.assign(y.begin(), y.end());
            }
            return unlocked([&] { return rig.set_trajectory(r); });
          },
          py::arg("shape"), py::arg("amplitude_m") = 0.0, py::arg("frequency_Hz") = 1.0, py::arg("offset_m") = 0.0,
          py::arg("phase_rad") = 0.0, py::arg("blend_s") = 1.0, py::arg("corner_s") = 0.0,
          py::arg("shape_if_infeasible") = false, py::arg("axis") = 0, py::arg("t_s") = py::none(),
          py::arg("y_m") = py::none(),
          R"(Compensator: the reference of `axis` (0 x): shape cosine|sine|triangle|hold|points, amplitude_m [m],
frequency_Hz [Hz], offset_m [m], phase_rad [rad], blend_s [s] from the previous reference,
corner_s [s] (triangle; 0: the compensator's choice), shape_if_infeasible (else refused);
points: t_s [s] and y_m [m]. Returns the compensator's verdict ('accepted...' or 'shaped: ...');
RigError when it refused it, with its reason.)")
      .def(
          "set_params",
          [](ctl::RigClient& rig, double c1, double c2, double c3, int axis, std::optional<std::int32_t> version,
             double residual_m) {
            ctl::ParamsRequest p;
            p.c1 = c1;
            p.c2 = c2;
            p.c3 = c3;
            p.axis = axis;
            p.version = version.value_or(0);
            p.residual_m = residual_m;
            return unlocked([&] { return rig.set_params(p); });
          },
          py::arg("c1"), py::arg("c2"), py::arg("c3"), py::arg("axis") = 0, py::arg("version") = py::none(),
          py::arg("residual_m") = 0.0,
          R"(HX_PARAMS: a MEM parameter set for `axis` (c1 [m/V], c2 [m/V^(1+c3)], c3 [-]); version None: one
above the highest heard. Returns the version once the compensator reports it in use.)")
      .def(
          "record",
          [](ctl::RigClient& rig, double seconds) {
            const ctl::RecordedTicks r = unlocked([&] { return rig.record(seconds); });
            return ticks_dict(r);
          },
          py::arg("seconds"),
          R"(Every tick of the sensor stream for `seconds` [s]: a dict of numpy arrays, one row per tick
and axis (seq, t_s [s], axis, u_V, u_ff_V, u_fb_V [V], y_ref_m, y_m, y_true_m [m] (NaN without a
simulated stage), flags), with axes, dt_s [s], blocks and missing_ticks (gaps while recording).)")
      .def(
          "next_block",
          [](ctl::RigClient& rig, double timeout) -> py::object {
            const auto r = unlocked([&] { return rig.next_block(timeout); });
            if (!r) return py::none();
            return ticks_dict(*r);
          },
          py::arg("timeout") = 1.0,
          "The next HX_SENSOR block's ticks as record() gives them, or None after `timeout` [s] without one.");
}

}  // namespace hystloop::python
