// hystloop.Model: every model of common/models that hystloop-model runs (models/model_descriptors.hpp's
// AllModels), configured through its parameter table with the same assignments, parsing and
// validation as hystloop-model's --param and --params-file, and run with the same loop. A model
// added to the registry appears here without new binding code.
#include <pybind11/stl.h>

#include <cmath>
#include <fstream>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "models/model_concepts.hpp"
#include "models/model_descriptors.hpp"
#include "models/param_text.hpp"
#include "model_loop.hpp"
#include "params_file.hpp"
#include "py_common.hpp"

namespace hystloop::python {
namespace {

template <class D>
class HandleFor final : public ModelHandle {
 public:
  using Forward = typename D::Forward;
  static constexpr bool kHasInverse = model_tool::kHasInverse<D>;

  explicit HandleFor(const typename D::Params& params) : params_(params) {}

  std::string_view name() const override { return D::name; }
  bool has_inverse() const override { return kHasInverse; }
  bool uses_time() const override { return !HysteresisForward<Forward>; }

  // hystloop-model's loops (tools/model/model_loop.hpp), over the caller's arrays.
  void forward(std::span<const double> t, std::span<const double> u, std::span<double> y) const override {
    model_tool::run_forward<D>(params_, t, u, y);
  }

  void inverse(std::span<const double> y_ref, std::span<double> u) const override {
    if constexpr (kHasInverse) {
      model_tool::run_inverse<D>(params_, y_ref, u);
    } else {
      throw std::logic_error(std::string(D::name) + " has no inverse");
    }
  }

  py::dict params() const override {
    const typename D::Settings s = D::settings_of(params_);
    py::dict out;
    for (const auto& row : D::table()) {
      if (row.applies != nullptr && !row.applies(s)) continue;  // as the YAML leaves it out
      const Assignment shown{std::string(row.name), row.show(s), std::string(row.name)};
      switch (row.kind) {
        case ValueKind::number: out[py::str(shown.name)] = py::float_(parse_number(shown)); break;
        case ValueKind::count: out[py::str(shown.name)] = py::int_(parse_count(shown)); break;
        case ValueKind::list: out[py::str(shown.name)] = py::cast(parse_list(shown)); break;
        case ValueKind::choice: out[py::str(shown.name)] = py::str(shown.value); break;
      }
    }
    return out;
  }

  // ident/params_yaml's section: the model's table over its settings, as hystloop-identify writes it.
  std::string yaml() const override { return yaml_section(D::name, D::table(), D::settings_of(params_)); }
  std::string summary() const override { return D::summary_of(params_); }

 private:
  typename D::Params params_;
};

struct ModelInfo {
  std::string_view name, summary, notes;
  bool has_inverse = false;
  bool uses_time = false;
  std::vector<ParamInfo> (*parameters)() = nullptr;
  std::unique_ptr<ModelHandle> (*configure)(const std::vector<Assignment>& assignments) = nullptr;
};

template <class D>
ModelInfo info_of() {
  return {D::name,
          D::summary,
          D::notes,
          HandleFor<D>::kHasInverse,
          !HysteresisForward<typename D::Forward>,
          [] { return describe(D::table()); },
          [](const std::vector<Assignment>& assignments) -> std::unique_ptr<ModelHandle> {
            return std::make_unique<HandleFor<D>>(params_from<D>(assignments));
          }};
}

const std::vector<ModelInfo>& registry() {
  static const std::vector<ModelInfo> models = [] {
    std::vector<ModelInfo> out;
    AllModels::for_each([&]<class D>() { out.push_back(info_of<D>()); });
    return out;
  }();
  return models;
}

std::string names(const char* separator = ", ") {
  std::string out;
  for (const auto& m : registry()) out += (out.empty() ? "" : separator) + std::string(m.name);
  return out;
}

// The model `name`, or a ParameterError as hystloop-model's --model refuses it.
const ModelInfo& find(const std::string& name) {
  std::vector<std::string> known;
  for (const auto& m : registry()) {
    if (m.name == name) return m;
    known.emplace_back(m.name);
  }
  const std::string guess = closest_name(name, known);
  throw PyParameterError("model", "unknown model '" + name + "'" +
                                      (guess.empty() ? "" : "; did you mean '" + guess + "'?") +
                                      " (models: " + names() + ")");
}

// A Python value as the text --param would carry: numbers in their shortest exact form, lists
// comma separated, strings as they are.
std::string value_text(py::handle v, const std::string& name) {
  if (py::isinstance<py::str>(v)) return v.cast<std::string>();
  if (py::isinstance<py::bool_>(v)) throw py::type_error(name + ": a number, an integer, a list or a text, not a bool");
  if (PyIndex_Check(v.ptr()) != 0) return py::str(py::int_(py::reinterpret_borrow<py::object>(v))).cast<std::string>();
  if (PyNumber_Check(v.ptr()) != 0) return format_number(py::float_(py::reinterpret_borrow<py::object>(v)));
  if (py::isinstance<py::iterable>(v)) {
    std::vector<double> values;
    for (py::handle item : v) values.push_back(py::float_(py::reinterpret_borrow<py::object>(item)));
    return format_list(values);
  }
  throw py::type_error(name + ": a number, an integer, a list or a text, not " +
                       py::str(py::type::handle_of(v).attr("__name__")).cast<std::string>());
}

// {"hysteresis": {"a": 1e-8}} and hysteresis__a=1e-8 are "hysteresis.a", as params files nest.
void flatten(py::handle mapping, const std::string& prefix, std::vector<Assignment>& out) {
  for (auto item : py::reinterpret_borrow<py::dict>(mapping)) {
    const std::string given = py::str(item.first).cast<std::string>();
    std::string key = prefix.empty() ? std::string() : prefix + ".";
    for (std::size_t i = 0; i < given.size(); ++i) {
      const bool dot = given[i] == '_' && i + 1 < given.size() && given[i + 1] == '_';
      key.push_back(dot ? '.' : given[i]);
      i += dot ? 1 : 0;
    }
    if (py::isinstance<py::dict>(item.second)) {
      flatten(item.second, key, out);
      continue;
    }
    const std::string text = value_text(item.second, key);
    std::string origin = key;
    origin.append("=").append(text);
    out.push_back({key, text, std::move(origin)});
  }
}

// Configures `info` with the assignments; refusals carry hystloop-model's messages.
std::unique_ptr<ModelHandle> configure(const ModelInfo& info, const std::vector<Assignment>& assignments) {
  try {
    return info.configure(assignments);
  } catch (const AssignmentError& e) {
    throw PyParameterError(e.field(), e.what());
  } catch (const ParameterError& e) {
    throw PyParameterError(e.field(), "model " + std::string(info.name) + ": " + e.what());
  }
}

class Model {
 public:
  explicit Model(std::shared_ptr<const ModelHandle> handle) : handle_(std::move(handle)) {}

  static Model make(const std::string& name, const py::object& params, const py::kwargs& kwargs) {
    const ModelInfo& info = find(name);
    std::vector<Assignment> assignments;
    if (!params.is_none()) {
      if (!py::isinstance<py::dict>(params)) throw py::type_error("params: a dict of parameter names to values");
      flatten(params, "", assignments);
    }
    flatten(kwargs, "", assignments);  // after the dict: a keyword overrides it
    return Model(configure(info, assignments));
  }

  static Model from_yaml(const std::string& path, const std::optional<std::string>& model) {
    model_tool::ParamsFile file;
    try {
      file = model_tool::read_params_file(path, model.value_or(""));
    } catch (const model_tool::ParamsFileError& e) {
      throw py::value_error(e.what());
    }
    return Model(configure(find(file.model), file.assignments));
  }

  std::string name() const { return std::string(handle_->name()); }
  const ModelHandle& handle() const { return *handle_; }

  py::array_t<double> forward(const InArray& u, const std::optional<InArray>& t) const {
    const std::span<const double> in = view_1d(u, "u");
    std::span<const double> times;
    if (handle_->uses_time()) {
      if (!t) {
        throw py::value_error("model " + name() +
                              " has dynamics: give t [s] (u[k] is held from t[k-1] to t[k]), as its CSV's t column");
      }
      times = view_1d(*t, "t");
      if (times.size() != in.size()) {
        throw py::value_error("t and u differ in length (" + std::to_string(times.size()) + " and " +
                              std::to_string(in.size()) + ")");
      }
      require_finite(times, "t");
      for (std::size_t k = 1; k < times.size(); ++k) {
        if (!(times[k] > times[k - 1])) {
          throw py::value_error("t[" + std::to_string(k) + "] = " + format_number(times[k]) +
                                " does not increase (t must increase)");
        }
      }
    }
    require_finite(in, "u");
    return run(in, times, true);
  }

  py::array_t<double> inverse(const InArray& y_ref) const {
    if (!handle_->has_inverse()) {
      throw py::value_error("model " + name() +
                            " has no inverse (a dynamic stage, not a static hysteresis map); run it forward, or use "
                            "an invertible model (mem, katalenic, pi, linear) for feedforward");
    }
    const std::span<const double> in = view_1d(y_ref, "y_ref");
    require_finite(in, "y_ref");
    return run(in, {}, false);
  }

  std::string yaml() const { return handle_->yaml(); }

  std::string to_yaml(const std::optional<std::string>& path) const {
    std::string text = handle_->yaml();
    if (path) {
      std::ofstream f(*path);
      f << "# written by hystloop.Model.to_yaml\n" << text;
      f.close();
      if (!f) throw py::value_error(*path + ": cannot write the parameters file");
    }
    return text;
  }

  std::string repr() const { return "hystloop.Model(" + name() + ": " + handle_->summary() + ")"; }

 private:
  py::array_t<double> run(std::span<const double> in, std::span<const double> t, bool forward) const {
    py::array_t<double> out = new_array(in.size());
    const std::span<double> result(out.mutable_data(), in.size());
    {
      const py::gil_scoped_release unlocked;
      if (forward) {
        handle_->forward(t, in, result);
      } else {
        handle_->inverse(in, result);
      }
    }
    for (std::size_t k = 0; k < result.size(); ++k) {
      if (!std::isfinite(result[k])) {
        PyErr_SetString(PyExc_FloatingPointError,
                        ("model " + name() + " gave a non-finite " + (forward ? "y" : "u") + " for " +
                         (forward ? "u" : "y_ref") + "[" + std::to_string(k) + "] = " + format_number(in[k]))
                            .c_str());
        throw py::error_already_set();
      }
    }
    return out;
  }

  std::shared_ptr<const ModelHandle> handle_;
};

py::dict info_dict(const ModelInfo& m) {
  py::list parameters;
  for (const ParamInfo& p : m.parameters()) {
    py::dict d;
    d["name"] = p.name;
    d["alias"] = p.alias;
    d["unit"] = p.unit;
    d["kind"] = p.kind;
    d["default"] = p.default_text;
    d["description"] = p.description;
    parameters.append(d);
  }
  py::dict out;
  out["name"] = std::string(m.name);
  out["summary"] = std::string(m.summary);
  out["notes"] = std::string(m.notes);
  out["has_inverse"] = m.has_inverse;
  out["uses_time"] = m.uses_time;
  out["parameters"] = parameters;
  return out;
}

}  // namespace

std::unique_ptr<ModelHandle> handle_of_set(const ModelParamSet& set) {
  std::unique_ptr<ModelHandle> out;
  OnlineModels::visit(set.kind, [&]<class D>() { out = std::make_unique<HandleFor<D>>(set.*D::in_set); });
  if (out == nullptr) throw std::logic_error("a parameter set of no known model");
  return out;
}

py::object wrap_model(std::unique_ptr<ModelHandle> handle) {
  return py::cast(Model(std::shared_ptr<const ModelHandle>(std::move(handle))));
}

void register_models(py::module_& m) {
  py::class_<Model>(m, "Model", R"doc(A hysteresis model of hystloop (common/models), the one hystloop-model runs.

Model(name, params=None, **kwargs)

name    one of hystloop.models(): mem, pi, katalenic, linear, banning (hystloop.model_info(name)
        lists each parameter with its unit, default and meaning).
params  a dict of parameter names to values; nested dicts or "a.b" keys for the dotted names
        (banning: {"hysteresis": {"a": 8.58e-9}} or {"hysteresis.a": 8.58e-9}).
kwargs  the same as keywords, after the dict (hysteresis__a=8.58e-9 for hysteresis.a).

Values are SI (V, m, m/V, s). Unnamed parameters keep their defaults. The set is checked by the
model's own validation: a refusal raises hystloop.ParameterError (a ValueError) with
hystloop-model's message, naming the field (.field).)doc")
      .def(py::init(&Model::make), py::arg("name"), py::arg("params") = py::none())
      .def_static("from_yaml", &Model::from_yaml, py::arg("path"), py::arg("model") = py::none(),
                  R"doc(from_yaml(path, model=None) -> Model

The parameters file hystloop-identify --out writes (and hystloop-model --params-file reads):
the top-level key is the model's name. model=None takes the file's only model section.
A file that cannot be read or holds no usable section raises ValueError.)doc")
      .def("forward", &Model::forward, py::arg("u"), py::arg("t") = py::none(),
           R"doc(forward(u, t=None) -> numpy.ndarray

u [V] -> y [m], a new float64 array of u's length; u is any 1-D array (float64 C-contiguous
input is read without copying). The model starts from its reset at u[0] (the first sample sets
the state), as hystloop-model --forward does. Models with dynamics (banning) need t [s], the
sample times: u[k] is held from t[k-1] to t[k]; static models ignore t.
Raises ValueError for a non-finite input, FloatingPointError if the model gives a non-finite y.)doc")
      .def("inverse", &Model::inverse, py::arg("y_ref"),
           R"doc(inverse(y_ref) -> numpy.ndarray

y_ref [m] -> u [V] (the feedforward), a new float64 array, starting from the state the forward
model reaches at y_ref[0], as hystloop-model --inverse does. ValueError for a model without an
inverse (banning) or a non-finite input.)doc")
      .def("to_yaml", &Model::to_yaml, py::arg("path") = py::none(),
           R"doc(to_yaml(path=None) -> str

The model's YAML section as hystloop-identify writes it (every number exact), written to path
when given; Model.from_yaml and hystloop-model --params-file read it back.)doc")
      .def_property_readonly("name", &Model::name, "the model's name (str)")
      .def_property_readonly(
          "params", [](const Model& self) { return self.handle().params(); },
          "the parameters as a dict (SI; the names of hystloop.model_info(name)); Model(name, **params) makes the "
          "same model")
      .def_property_readonly(
          "has_inverse", [](const Model& self) { return self.handle().has_inverse(); }, "whether inverse() exists")
      .def_property_readonly(
          "uses_time", [](const Model& self) { return self.handle().uses_time(); }, "whether forward() needs t")
      .def_property_readonly(
          "summary", [](const Model& self) { return self.handle().summary(); }, "one line: the main values")
      .def("__repr__", &Model::repr);

  m.def(
      "models",
      [] {
        std::vector<std::string> out;
        for (const auto& info : registry()) out.emplace_back(info.name);
        return out;
      },
      "models() -> list[str]: the names of every model Model() takes, in hystloop-model's order");
  m.def(
      "model_info", [](const std::string& name) { return info_dict(find(name)); }, py::arg("name"),
      R"doc(model_info(name) -> dict

name, summary, notes, has_inverse, uses_time and parameters: a list of dicts with name, alias,
unit, kind (number, integer, list, or the choices "a|b"), default (as text) and description.)doc");
}

}  // namespace hystloop::python
