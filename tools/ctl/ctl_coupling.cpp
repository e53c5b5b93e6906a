#include "ctl_coupling.hpp"

#include <cmath>
#include <cstdio>

#include <spdlog/fmt/fmt.h>

#include "core/errors.hpp"

namespace hystloop::ctl {

void CouplingRunOptions::validate() const {
  require_in_range("amplitude", amplitude_V, 1.0, 1000.0);
  require_in_range("offset", offset_V, -1000.0, 1000.0);
  require_in_range("frequency", frequency_Hz, 0.1, 1000.0);
  require_positive("duration", duration_s);
  if (duration_s * frequency_Hz < 1.0) throw ParameterError("duration", "must cover at least one period");
  require_non_negative("rest", rest_s);
  require_positive("timeout", timeout_s);
}

ExperimentRequest coupling_experiment(const CouplingRunOptions& o) {
  return sine_experiment(o.offset_V, o.amplitude_V, o.frequency_Hz, o.duration_s);
}

CouplingFitResult fit_records(const std::vector<CouplingRecord>& records, int axes) {
  std::vector<AxisExcitation> experiments;
  for (const CouplingRecord& r : records) {
    AxisExcitation x;
    x.axis = r.axis;
    for (int j = 0; j < axes; ++j) x.y_m[static_cast<std::size_t>(j)] = r.y_m[static_cast<std::size_t>(j)];
    experiments.push_back(x);
  }
  CouplingFitOptions fit;
  fit.axes = axes;
  return fit_coupling(experiments, fit);
}

std::string describe_fit(const CouplingFitResult& fit, int axes) {
  std::string out;
  for (int i = 0; i < axes; ++i) {
    for (int j = 0; j < axes; ++j) {
      if (i == j) continue;
      out += fmt::format("  {} -> {}: {:+.5f} +- {:.1e} (line residual {:.2f} nm)\n", axis_name(i), axis_name(j),
                         fit.estimate(j, i), fit.standard_error(j, i), fit.line_residual_rms_m(j, i) * 1e9);
    }
  }
  return out;
}

std::string decoupling_yaml(const CouplingFitResult& fit, int axes, const std::string& origin) {
  std::string out = "# The stage's coupling C (decoupling.<from>_to_<to> is C(to, from)), identified by " + origin +
                    ";\n# hystloop-compensator --params <this file> cancels it.\ndecoupling:\n";
  for (int i = 0; i < axes; ++i) {
    for (int j = 0; j < axes; ++j) {
      if (i == j) continue;
      out += fmt::format("  {}_to_{}: {:.6g}   # +- {:.1e}\n", axis_name(i), axis_name(j), fit.coupling.matrix()(j, i),
                         fit.standard_error(j, i));
    }
  }
  return out;
}

}  // namespace hystloop::ctl
