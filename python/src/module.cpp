// The extension hystloop._core: the three parts (py_models, py_identify, py_log) and what they share.
#include <cmath>
#include <string>

#include "py_common.hpp"

namespace hystloop::python {

std::span<const double> view_1d(const InArray& a, const char* what) {
  if (a.ndim() != 1) {
    throw py::value_error(std::string(what) + ": expected a 1-D array, got " + std::to_string(a.ndim()) +
                          " dimensions");
  }
  return {a.data(), static_cast<std::size_t>(a.shape(0))};
}

py::array_t<double> new_array(std::size_t n) { return py::array_t<double>(static_cast<py::ssize_t>(n)); }

void require_finite(std::span<const double> v, const char* what) {
  for (std::size_t k = 0; k < v.size(); ++k) {
    if (!std::isfinite(v[k])) {
      throw py::value_error(std::string(what) + "[" + std::to_string(k) + "] = " + std::to_string(v[k]) +
                            ": not a finite number");
    }
  }
}

}  // namespace hystloop::python

PYBIND11_MODULE(_core, m) {
  namespace py = pybind11;
  using namespace hystloop::python;
  m.doc() =
      "hystloop's models, identification, log reader and rig client: the C++ code of hystloop-model, "
      "hystloop-identify, hystloop-report and hystloop-ctl, numpy arrays in and out (SI units: s, V, m).";

  // hystloop.ParameterError(ValueError): .field names the refused parameter or option.
  static py::exception<PyParameterError> parameter_error(m, "ParameterError", PyExc_ValueError);
  // hystloop.FitError(RuntimeError): .status, .reason, .result (the IdentifyResult with its ranking).
  static py::exception<PyFitError> fit_error(m, "FitError", PyExc_RuntimeError);
  // pybind11 takes a void (*)(std::exception_ptr): by value.
  py::register_exception_translator([](std::exception_ptr p) {  // NOLINT(performance-unnecessary-value-param)
    try {
      if (p) std::rethrow_exception(p);
    } catch (const PyParameterError& e) {
      py::object error = py::reinterpret_borrow<py::object>(parameter_error)(e.what());
      error.attr("field") = e.field();
      PyErr_SetObject(parameter_error.ptr(), error.ptr());
    } catch (const PyFitError& e) {
      py::object error = py::reinterpret_borrow<py::object>(fit_error)(e.what());
      error.attr("status") = e.status();
      error.attr("reason") = e.reason();
      error.attr("result") = e.result();
      PyErr_SetObject(fit_error.ptr(), error.ptr());
    }
  });

  register_models(m);
  register_identify(m);
  register_banning(m);
  register_log(m);
  register_rig(m);
  register_stage(m);
}
