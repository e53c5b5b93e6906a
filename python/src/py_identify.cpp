// hystloop.identify: hystloop-identify's fit of one record (tools/identify/identify_run.cpp's
// fit_single and fit_auto) on numpy arrays: the same sanity checks, decimation, sample budget,
// fitters and model selection (common/ident), the same set and YAML, the same refusals.
#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ident/fit_checks.hpp"
#include "ident/model_selection.hpp"
#include "ident/sample_csv.hpp"
#include "py_common.hpp"
#include "sample_budget.hpp"

namespace hystloop::python {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Ranked {
  std::string model, status, reason;
  double residual_m = kNaN, heldout_rms_m = kNaN, fit_time_s = kNaN;
  std::size_t samples_used = 0;
};

struct IdentifyResult {
  std::string requested, model, status = "ok", reason;
  py::object fitted = py::none();  // hystloop.Model
  double residual_m = kNaN, heldout_rms_m = kNaN, fit_time_s = kNaN, window_s = kNaN;
  std::size_t samples = 0, samples_used = 0;
  std::optional<std::size_t> split_index;
  std::vector<Ranked> ranking;
  std::string yaml;
  py::dict details;
  bool ok() const { return status == "ok"; }
};

struct Options {
  std::string model = "auto";
  std::string form = "integrated";
  double noise_rms_m = 0.0;
  double min_snr = 3.0;
  std::size_t operators = 15;
  int katalenic_degree = 1;
  std::size_t decimate = 1;
  std::size_t max_samples = kDefaultMaxSamples;
};

// The checks hystloop-identify's command line makes on these options (CLI11's ranges), then the
// fitters' own validation.
ModelSelectionOptions selection_options(const Options& a) {
  if (a.form != "integrated" && a.form != "derivative")
    throw PyParameterError("form", "form: '" + a.form + "' is not one of integrated, derivative");
  if (!(a.noise_rms_m >= 0.0) || !std::isfinite(a.noise_rms_m))
    throw PyParameterError("noise_rms_m", "noise_rms_m: must be a finite number >= 0 (0 = estimate from the data)");
  if (!(a.min_snr >= 0.0) || !std::isfinite(a.min_snr))
    throw PyParameterError("min_snr", "min_snr: must be a finite number >= 0");
  if (a.operators < 1 || a.operators > 32)
    throw PyParameterError("operators", "operators: " + std::to_string(a.operators) + " is not in [1, 32]");
  if (a.katalenic_degree < 1 || a.katalenic_degree > 7)
    throw PyParameterError("katalenic_degree",
                           "katalenic_degree: " + std::to_string(a.katalenic_degree) + " is not in [1, 7]");
  if (a.decimate < 1) throw PyParameterError("decimate", "decimate: must be >= 1");
  if (a.max_samples < 1) throw PyParameterError("max_samples", "max_samples: must be >= 1");
  // As identify_run.cpp's selection_options.
  ModelSelectionOptions o;
  o.mem.form = a.form == "derivative" ? MemFitForm::derivative : MemFitForm::integrated;
  o.mem.noise_rms_m = a.noise_rms_m;
  o.mem.min_snr = a.min_snr;
  o.pi.operators = a.operators;
  o.katalenic.output_polynomial_degree = a.katalenic_degree;
  try {
    o.validate();
  } catch (const ParameterError& e) {
    throw PyParameterError(e.field(), e.what());
  }
  return o;
}

double window_of(const SampleTable& s, std::size_t end) {
  return end < 2 || s.t.size() < end ? 0.0 : s.t[end - 1] - s.t.front();
}

void fail(IdentifyResult& r, FitStatus status, const std::string& reason) {
  r.status = std::string(to_string(status));
  r.reason = reason;
}

// The set `fit` holds for `kind` (identify_run.cpp's take_set); false when it makes no valid set.
bool take_set(const ModelSelection& fit, ModelKind kind, IdentifyResult& r) {
  ModelParamSet set;
  try {
    set = fitted_set(fit, kind);
  } catch (const ParameterError& e) {
    fail(r, FitStatus::out_of_range, e.what());
    return false;
  }
  std::unique_ptr<ModelHandle> handle = handle_of_set(set);
  r.yaml = handle->yaml();
  r.fitted = wrap_model(std::move(handle));
  return true;
}

Ranked ranked(const ModelScore& s) {
  return {std::string(to_string(s.kind)),
          std::string(to_string(s.status)),
          s.reason,
          s.train_rms_m,
          s.holdout_rms_m,
          s.fit_time_s,
          s.samples_used};
}

IdentifyResult identify(const InArray& t_in, const InArray& u_in, const InArray& y_in, const Options& a, bool check) {
  IdentifyResult r;
  r.requested = a.model;
  std::optional<ModelKind> kind;
  if (a.model != "auto") {
    kind = parse_model_kind(a.model);
    if (!kind) {
      std::string hint = "one of auto";  // and every model parse_model_kind knows
      for (const std::string_view name : model_kind_names()) hint += ", " + std::string(name);
      if (a.model == "banning")
        hint = "Banning's model is fitted on a series of experiments: hystloop-identify --model banning";
      throw PyParameterError("model", "model " + a.model + ": unknown here (" + hint + ")");
    }
  }
  const ModelSelectionOptions o = selection_options(a);
  const std::span<const double> t = view_1d(t_in, "t"), u = view_1d(u_in, "u"), y = view_1d(y_in, "y");
  if (t.size() != u.size() || u.size() != y.size()) {
    throw PyParameterError("t/u/y", "t, u and y differ in length (" + std::to_string(t.size()) + ", " +
                                        std::to_string(u.size()) + ", " + std::to_string(y.size()) + ")");
  }
  require_finite(t, "t");
  // What the CSV reader refuses (sample_csv.hpp): non-finite values, values beyond the sanity bounds.
  if (const FitCheck c = check_fit_samples(u, y); !c.ok()) throw PyParameterError("u/y", c.reason);
  const std::size_t samples = (u.size() + a.decimate - 1) / a.decimate;
  if (auto why = over_sample_budget(samples, a.max_samples, a.decimate)) throw PyParameterError("max_samples", *why);
  SampleTable s{{t.begin(), t.end()}, {u.begin(), u.end()}, {y.begin(), y.end()}, {}};

  ModelSelection sel;
  ModelScore score;
  {
    const py::gil_scoped_release unlocked;
    decimate(s, a.decimate, true);  // the models are rate independent: the turning points are kept
    if (kind) {
      score = fit_candidate(*kind, s.u, s.y, o, sel);
    } else {
      sel = select_model(s.u, s.y, o);
    }
  }
  r.samples = s.u.size();
  if (kind) {
    r.model = a.model;
    r.ranking.push_back(ranked(score));
    if (score.status != FitStatus::ok) {
      fail(r, score.status, score.reason);
    } else if (take_set(sel, *kind, r)) {
      r.residual_m = score.train_rms_m;
      r.samples_used = score.samples_used;
      r.fit_time_s = score.fit_time_s;
      r.window_s = window_of(s, s.t.size());
      if (*kind == ModelKind::mem) {
        r.details["form"] = a.form;
        r.details["noise_rms_m"] = sel.mem.noise_rms_m;
        r.details["branches_used"] = sel.mem.branches_used;
        r.details["constrained"] = sel.mem.constrained;
      } else if (*kind == ModelKind::pi) {
        r.details["offset_m"] = sel.pi.offset_m;  // PiParams has no offset: a PI model starts at 0
      }
    }
  } else {
    for (const ModelScore& m : sel.ranking) r.ranking.push_back(ranked(m));
    r.split_index = sel.split_index;
    if (!sel.ok()) {
      fail(r, sel.status, sel.reason);
    } else {
      const ModelScore& best = sel.ranking.front();
      r.model = std::string(to_string(best.kind));
      if (take_set(sel, best.kind, r)) {
        r.residual_m = best.train_rms_m;
        r.heldout_rms_m = best.holdout_rms_m;
        r.samples_used = best.samples_used;
        r.fit_time_s = best.fit_time_s;
        r.window_s = window_of(s, sel.split_index + 1);
      }
    }
  }
  if (check && !r.ok()) throw PyFitError(r.status, r.reason, py::cast(r));
  return r;
}

std::string repr(const IdentifyResult& r) {
  if (!r.ok()) return "hystloop.IdentifyResult(" + r.requested + ": no fit (" + r.status + "): " + r.reason + ")";
  return "hystloop.IdentifyResult(" + r.model + ", residual " + number_text(r.residual_m * 1e9, 4) +
         " nm RMS, held out " + number_text(r.heldout_rms_m * 1e9, 4) +
         " nm RMS: " + py::str(r.fitted.attr("summary")).cast<std::string>() + ")";
}

}  // namespace

void register_identify(py::module_& m) {
  py::class_<Ranked>(m, "RankedModel", "one model's line of identify's ranking")
      .def_readonly("model", &Ranked::model, "the model's name")
      .def_readonly("status", &Ranked::status, "ok, or why it was refused (too_few_branches, out_of_range, ...)")
      .def_readonly("reason", &Ranked::reason, "the refusal's reason ('' when ok)")
      .def_readonly("residual_m", &Ranked::residual_m, "fit residual [m RMS] as the fitter reports it")
      .def_readonly("heldout_rms_m", &Ranked::heldout_rms_m,
                    "prediction error on the held-out part [m RMS] (auto only; 0 for a single model)")
      .def_readonly("fit_time_s", &Ranked::fit_time_s, "the fitter's time [s]")
      .def_readonly("samples_used", &Ranked::samples_used, "samples the fitter used")
      .def("__repr__", [](const Ranked& r) {
        return "hystloop.RankedModel(" + r.model + ", " + r.status + ", residual " +
               number_text(r.residual_m * 1e9, 4) + " nm, held out " + number_text(r.heldout_rms_m * 1e9, 4) + " nm" +
               (r.reason.empty() ? "" : ": " + r.reason) + ")";
      });

  py::class_<IdentifyResult>(m, "IdentifyResult", "what hystloop.identify found (hystloop-identify's output)")
      .def_readonly("requested", &IdentifyResult::requested, "the model asked for: auto or a model's name")
      .def_readonly("model", &IdentifyResult::model, "the model fitted (auto: the best ranked); '' if none")
      .def_readonly("status", &IdentifyResult::status, "ok, or the fit's refusal (FitStatus: too_few_branches, ...)")
      .def_readonly("reason", &IdentifyResult::reason, "why there is no fit ('' when ok)")
      .def_property_readonly("ok", &IdentifyResult::ok, "status == 'ok'")
      .def_readonly("fitted", &IdentifyResult::fitted, "the fitted set as a hystloop.Model (None without a fit)")
      .def_property_readonly(
          "params",
          [](const IdentifyResult& r) { return r.fitted.is_none() ? py::dict() : py::dict(r.fitted.attr("params")); },
          "the fitted parameters (dict, SI), as in the YAML")
      .def_readonly("residual_m", &IdentifyResult::residual_m, "fit residual on the whole record [m RMS]")
      .def_readonly("heldout_rms_m", &IdentifyResult::heldout_rms_m,
                    "auto: the best model's prediction error on the held-out part [m RMS]; NaN for one model")
      .def_readonly("fit_time_s", &IdentifyResult::fit_time_s, "the fitter's time [s]")
      .def_readonly("window_s", &IdentifyResult::window_s, "the time span fitted [s]")
      .def_readonly("samples", &IdentifyResult::samples, "samples after decimation")
      .def_readonly("samples_used", &IdentifyResult::samples_used, "samples the fitter used")
      .def_readonly("split_index", &IdentifyResult::split_index, "auto: the first held-out sample; None otherwise")
      .def_readonly("ranking", &IdentifyResult::ranking,
                    "auto: every model, best first, refused ones last (list of RankedModel); one model: its line")
      .def_readonly("yaml", &IdentifyResult::yaml, "the YAML snippet hystloop-identify prints and writes ('' if none)")
      .def_readonly("details", &IdentifyResult::details,
                    "mem: form, noise_rms_m [m], branches_used, constrained; pi: offset_m [m] (not in the set)")
      .def(
          "to_yaml",
          [](const IdentifyResult& r, const std::string& path) {
            if (r.fitted.is_none()) throw py::value_error("no fit (" + r.status + "): " + r.reason);
            return r.fitted.attr("to_yaml")(path);
          },
          py::arg("path"), "writes the fitted set as hystloop-identify --out does; Model.from_yaml reads it")
      .def("__repr__", &repr);

  m.def(
      "identify",
      [](const InArray& t, const InArray& u, const InArray& y, const std::string& model, const std::string& form,
         double noise_rms_m, double min_snr, std::size_t operators, int katalenic_degree, std::size_t decimate,
         std::size_t max_samples, bool check) {
        const Options o{model, form, noise_rms_m, min_snr, operators, katalenic_degree, decimate, max_samples};
        return identify(t, u, y, o, check);
      },
      py::arg("t"), py::arg("u"), py::arg("y"), py::arg("model") = "auto", py::kw_only(),
      py::arg("form") = "integrated", py::arg("noise_rms_m") = 0.0, py::arg("min_snr") = 3.0, py::arg("operators") = 15,
      py::arg("katalenic_degree") = 1, py::arg("decimate") = 1, py::arg("max_samples") = kDefaultMaxSamples,
      py::arg("check") = true,
      R"doc(identify(t, u, y, model="auto", *, form="integrated", noise_rms_m=0.0, min_snr=3.0, operators=15,
         katalenic_degree=1, decimate=1, max_samples=2000000, check=True) -> IdentifyResult

Fits a hysteresis model to one record, as hystloop-identify does with a t,u,y CSV (same code,
same numbers to the last bit):
  t [s], u [V], y [m]   1-D arrays of one length (one axis's samples; read_log(...) gives them
                        per axis)
  model                 "auto" (every model fitted on the first part and ranked on the held-out
                        rest; the best one returned), or one of "mem", "pi", "katalenic", "linear"
                        (fitted on the whole record)
  form                  MEM data form: "integrated" branches or the paper's "derivative"
  noise_rms_m           sensor noise RMS [m]; 0 = estimated from the data
  min_snr               MEM derivative form: keep points with at least this SNR
  operators             PI: number of play operators (1..32)
  katalenic_degree      Katalenic: output shaping polynomial degree (1..7; 1 = linear)
  decimate              keep every K-th sample and the input's turning points between them
  max_samples           refuse more samples than this (after decimate): a fit holds its problem in memory
  check                 True: a fit that finds no model raises hystloop.FitError ("no fit (status):
                        reason", with .result); False: the result says so (status, reason)
Data or options hystloop-identify refuses (lengths, non-finite values, values beyond 10 kV or
1 m, an unknown model, an option out of range, too many samples) raise hystloop.ParameterError.)doc");
}

}  // namespace hystloop::python
