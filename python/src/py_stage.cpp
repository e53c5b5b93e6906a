// hystloop.identify_stage: a stage's linear dynamics from a periodic multisine record on numpy
// arrays, by ident/stage_identification.hpp (the robust method's FRF and its uncertainty, then
// Sanathanan-Koerner iterations refined by Ceres, with delay and the exact zero-order hold): the
// same steps hystloop-identify --model stage takes on a log or a CSV.
#include <pybind11/complex.h>
#include <pybind11/stl.h>

#include <complex>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/errors.hpp"
#include "ident/stage_hysteresis_fit.hpp"
#include "ident/stage_identification.hpp"
#include "models/multisine.hpp"
#include "py_common.hpp"

namespace hystloop::python {
namespace {

using C = std::complex<double>;

std::vector<C> roots_hz(const std::vector<C>& roots_rad_s) {
  std::vector<C> out;
  out.reserve(roots_rad_s.size());
  for (const C r : roots_rad_s) out.push_back(r / (2.0 * std::numbers::pi));
  return out;
}

py::dict identify_stage(const InArray& u_in, const InArray& y_in, double sample_rate_Hz, std::size_t period_samples,
                        std::size_t periods, std::size_t realisations, std::size_t transient_periods,
                        const std::optional<std::pair<double, double>>& band, const std::string& order, int max_order,
                        double max_delay_s, bool continuous, bool sampled_at_tick_end, std::size_t hysteresis_plays) {
  const std::span<const double> u = view_1d(u_in, "u"), y = view_1d(y_in, "y");
  StageFitOptions o;
  o.unit_dc_gain = false;  // the data carry the actuator's gain: reported as dc_gain
  o.zoh_sample_rate_Hz = continuous ? 0.0 : sample_rate_Hz;
  o.max_delay_s = max_delay_s;
  o.max_order = max_order;
  FrfOptions fo;
  fo.sample_rate_Hz = sample_rate_Hz;
  fo.period_samples = period_samples;
  fo.periods = periods;
  fo.realisations = realisations;
  fo.transient_periods = transient_periods;
  StageIdentification id;
  HysteresisStageIdentification through;
  double dc_gain = 0.0;
  try {
    set_stage_order(order, o);
    fo.validate();
    MultisineOptions mo;
    mo.sample_rate_Hz = sample_rate_Hz;
    mo.period_samples = period_samples;
    if (band) {
      mo.f_min_Hz = band->first;
      mo.f_max_Hz = band->second;
    } else {
      mo.f_min_Hz = sample_rate_Hz / static_cast<double>(period_samples);
      mo.f_max_Hz = 0.45 * sample_rate_Hz;
    }
    const std::vector<std::size_t> lines = multisine_lines(mo);
    if (hysteresis_plays > 0) {
      HysteresisStageOptions ho;
      ho.operators = hysteresis_plays;
      through = identify_stage_with_hysteresis(u, y, lines, fo, o, sampled_at_tick_end, ho);
      dc_gain = through.linear.fit.dc_gain;
      // A series model that could not be fitted leaves the stage from u -> y, as with 0 plays.
      id = through.ok() && through.rounds > 0 ? through.stage : through.linear;
    } else {
      id = identify_stage_dynamics(u, y, lines, fo, o, sampled_at_tick_end);
      dc_gain = id.fit.dc_gain;
    }
  } catch (const ParameterError& e) {
    throw PyParameterError(e.field(), e.what());
  }
  if (!id.ok()) throw PyParameterError("u", id.reason());
  const FrequencyResponse& frf = id.frf;
  const StageFitResult& fit = id.fit;
  const std::vector<double>& sigma = id.sigma();
  std::vector<C> model;
  model.reserve(frf.frequency_Hz.size());
  for (const double f : frf.frequency_Hz) model.push_back(fit.sampled_response(f));
  py::dict d;
  d["frequency_Hz"] = frf.frequency_Hz;
  d["G"] = frf.G;
  d["sigma"] = sigma;
  d["sigma_noise"] = frf.sigma_noise;
  d["coherence"] = frf.coherence;
  d["model_G"] = model;
  d["dc_gain"] = dc_gain;
  const bool series = through.ok() && through.rounds > 0;
  d["through_hysteresis"] = series;
  d["hysteresis_thresholds_V"] = series ? through.thresholds_V : std::vector<double>{};
  d["hysteresis_weights"] = series ? through.weights : std::vector<double>{};
  d["residual_rms"] = series ? through.residual_rms : std::numeric_limits<double>::quiet_NaN();
  d["residual_rms_linear"] = series ? through.residual_rms_linear : std::numeric_limits<double>::quiet_NaN();
  d["hysteresis_not_kept"] = through.not_kept;
  d["poles_hz"] = roots_hz(fit.poles_rad_s);
  d["zeros_hz"] = roots_hz(fit.zeros_rad_s);
  d["delay_s"] = fit.delay_s;
  d["order"] = std::to_string(fit.numerator_order) + "/" + std::to_string(fit.denominator_order);
  d["chi2_per_line"] = fit.chi2_per_line;
  d["chi2_expected"] = fit.chi2_expected;
  d["order_consistent"] = fit.order_consistent;
  d["distortion_ratio"] = frf.distortion_ratio;
  return d;
}

}  // namespace

void register_stage(py::module_& m) {
  m.def("identify_stage", &identify_stage, py::arg("u"), py::arg("y"), py::kw_only(), py::arg("sample_rate_Hz") = 1e4,
        py::arg("period_samples"), py::arg("periods"), py::arg("realisations") = 1, py::arg("transient_periods") = 1,
        py::arg("band") = py::none(), py::arg("order") = "auto", py::arg("max_order") = 8,
        py::arg("max_delay_s") = 1e-3, py::arg("continuous") = false, py::arg("sampled_at_tick_end") = true,
        py::arg("hysteresis_plays") = 0,
        R"doc(identify_stage(u, y, *, sample_rate_Hz=1e4, period_samples, periods, realisations=1,
               transient_periods=1, band=None, order="auto", max_order=8, max_delay_s=1e-3,
               continuous=False, sampled_at_tick_end=True, hysteresis_plays=0) -> dict

A stage's linear dynamics from a periodic multisine record (hystloop-ctl experiment multisine,
or any periodic excitation), the steps of hystloop-identify --model stage:
  u [V], y [m]          1-D arrays of realisations * periods * period_samples samples
  band                  (f_min_Hz, f_max_Hz) of the excited lines; None: every line up to 0.45 fs
  transient_periods     dropped at the start of each realisation
  order                 "NUM/DEN" (e.g. "2/4") or "auto" (the lowest order whose residual is the
                        uncertainty's, up to max_order)
  continuous            the data were not held and sampled (no zero-order hold in the model)
  sampled_at_tick_end   y_k measured at the end of tick k (a hystloop bridge): the data are moved
                        by that tick so that delay_s is the rig's own
  hysteresis_plays      play operators of a Prandtl-Ishlinskii hysteresis fitted together with the
                        stage (as hystloop-identify --hysteresis-plays, whose default is 15): the
                        stage is measured from the hysteresis' output H(u), with unit DC gain; 0
                        (the default here, G in m/V as before): from u -> y alone
Returns frequency_Hz, G and sigma (its standard deviation, from periods and realisations; from H(u)
to y, unit DC gain, when through_hysteresis, else from u to y [m/V]), sigma_noise, coherence,
model_G (the fitted model's response, as sampled, in G's units), dc_gain [m/V] (u -> y), poles_hz
and zeros_hz (s / 2 pi, complex), delay_s [s], order, chi2_per_line against chi2_expected,
order_consistent, distortion_ratio; through_hysteresis, hysteresis_thresholds_V and
hysteresis_weights [m/V] (H's plays), residual_rms and residual_rms_linear (what G(H(u)) and the
u -> y fit leave of the record [m]; NaN without the hysteresis), hysteresis_not_kept (why a round
through the hysteresis was not kept: its residual above 1.1 times u -> y's; empty
otherwise). Refusals raise
hystloop.ParameterError.)doc");
}

}  // namespace hystloop::python
