#pragma once
// What the three parts of the Python module share: numpy arrays in and out, the refusals as Python
// exceptions, and the model handle identify returns its fitted set in.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstddef>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "models/model_set.hpp"
#include "models/param_table.hpp"

namespace hystloop::python {

namespace py = pybind11;

// A float64 array as numpy hands it over: float64 C-contiguous input is read in place, anything
// else (another dtype, a strided view, a list) is converted once by pybind11.
using InArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// A parameter or value refused (Python: hystloop.ParameterError, a ValueError with .field).
class PyParameterError : public std::invalid_argument {
 public:
  PyParameterError(std::string field, const std::string& message)
      : std::invalid_argument(message), field_(std::move(field)) {}
  const std::string& field() const noexcept { return field_; }

 private:
  std::string field_;
};

// A fit that found no model (Python: hystloop.FitError, a RuntimeError with .status and .reason).
class PyFitError : public std::runtime_error {
 public:
  PyFitError(std::string status, std::string reason, py::object result)
      : std::runtime_error("no fit (" + status + "): " + reason),
        status_(std::move(status)),
        reason_(std::move(reason)),
        result_(std::move(result)) {}
  const std::string& status() const noexcept { return status_; }
  const std::string& reason() const noexcept { return reason_; }
  const py::object& result() const noexcept { return result_; }

 private:
  std::string status_, reason_;
  py::object result_;
};

// The 1-D data of `a`; throws ValueError naming `what` when it is not one-dimensional.
std::span<const double> view_1d(const InArray& a, const char* what);
// A new float64 array of n elements.
py::array_t<double> new_array(std::size_t n);
// Throws ValueError naming `what`, the first non-finite element and its index.
void require_finite(std::span<const double> v, const char* what);

// One configured model of common/models (any descriptor of AllModels): runs it, shows its values.
class ModelHandle {
 public:
  virtual ~ModelHandle() = default;
  virtual std::string_view name() const = 0;
  virtual bool has_inverse() const = 0;
  virtual bool uses_time() const = 0;
  // hystloop-model's loops: forward from reset(u[0]); a stage steps u[k] held from t[k-1] to t[k].
  virtual void forward(std::span<const double> t, std::span<const double> u, std::span<double> y) const = 0;
  virtual void inverse(std::span<const double> y_ref, std::span<double> u) const = 0;
  // The parameters as the YAML would hold them: (name, value as Python object) in table order.
  virtual py::dict params() const = 0;
  virtual std::string yaml() const = 0;     // the section hystloop-identify writes
  virtual std::string summary() const = 0;  // "c1 5.3e-09 m/V, ..."
};

// The handle of an online model's set (identify's fitted set), and a Python hystloop.Model around one.
std::unique_ptr<ModelHandle> handle_of_set(const ModelParamSet& set);
py::object wrap_model(std::unique_ptr<ModelHandle> handle);

void register_models(py::module_& m);
void register_identify(py::module_& m);
void register_banning(py::module_& m);
void register_log(py::module_& m);
void register_rig(py::module_& m);
void register_stage(py::module_& m);

}  // namespace hystloop::python
