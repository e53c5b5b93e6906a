#include "ident/coupling_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <utility>

#include "core/errors.hpp"
#include "ident/fit_checks.hpp"
#include "ident/fit_clock.hpp"

namespace hystloop {

void CouplingFitOptions::validate() const {
  if (axes < 1 || axes > kMaxAxes) {
    throw ParameterError("axes", "must be in [1, " + std::to_string(kMaxAxes) + "] (got " + std::to_string(axes) + ")");
  }
  require_positive("min_travel_m", min_travel_m);
  if (min_samples < 3) {
    // A line has 2 parameters; its standard error needs a residual.
    throw ParameterError("min_samples", "must be >= 3 (got " + std::to_string(min_samples) + ")");
  }
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// "experiment 2 (y moved)": how a reason names the data it refuses.
std::string experiment_label(std::size_t k, int axis) {
  std::ostringstream s;
  s << "experiment " << k << " (" << axis_name(axis) << " moved)";
  return s.str();
}

// One experiment per axis 0..n-1: writes which experiment moved each axis (-1: none) to *moved_by.
FitCheck check_experiment_axes(std::span<const AxisExcitation> experiments, const CouplingFitOptions& options,
                               std::array<int, kMaxAxes>* moved_by) {
  const int n = options.axes;
  moved_by->fill(-1);
  if (experiments.empty()) return {FitStatus::too_few_samples, "no experiments: nothing to identify"};
  for (std::size_t k = 0; k < experiments.size(); ++k) {
    const int axis = experiments[k].axis;
    if (axis < 0 || axis >= n) {
      std::ostringstream s;
      s << "experiment " << k << " moves axis " << axis << ", but the fit has " << n << " axes (0.." << n - 1 << ")";
      return {FitStatus::out_of_range, s.str()};
    }
    const auto a = static_cast<std::size_t>(axis);
    if ((*moved_by)[a] >= 0) {
      std::ostringstream s;
      s << "axis " << axis_name(axis) << " is moved by experiments " << (*moved_by)[a] << " and " << k
        << ": give one experiment per axis";
      return {FitStatus::size_mismatch, s.str()};
    }
    (*moved_by)[a] = static_cast<int>(k);
  }
  if (!options.allow_unexcited_axes) {
    for (int i = 0; i < n; ++i) {
      if ((*moved_by)[static_cast<std::size_t>(i)] < 0) {
        std::ostringstream s;
        s << "no experiment moves axis " << axis_name(i) << ", so its effect on the other axes is unknown (move it, "
          << "or set allow_unexcited_axes to take it as uncoupled)";
        return {FitStatus::too_few_samples, s.str()};
      }
    }
  }
  return {};
}

// Lengths, finiteness, sanity bound and the moved axis's travel of experiment k.
FitCheck check_experiment_samples(const AxisExcitation& e, std::size_t k, const CouplingFitOptions& options) {
  const int n = options.axes;
  const auto moved = static_cast<std::size_t>(e.axis);
  const std::size_t len = e.y_m[moved].size();
  for (int j = 0; j < kMaxAxes; ++j) {
    const std::span<const double> y = e.y_m[static_cast<std::size_t>(j)];
    std::ostringstream s;
    if (j < n && y.size() != len) {
      s << experiment_label(k, e.axis) << ": " << axis_name(j) << " has " << y.size() << " samples, "
        << axis_name(e.axis) << " has " << len;
      return {FitStatus::size_mismatch, s.str()};
    }
    if (j >= n && !y.empty()) {
      s << experiment_label(k, e.axis) << ": " << axis_name(j) << " has " << y.size() << " samples, but the fit has "
        << n << " axes";
      return {FitStatus::size_mismatch, s.str()};
    }
  }
  if (len < options.min_samples) {
    std::ostringstream s;
    s << experiment_label(k, e.axis) << ": " << len << " samples (need " << options.min_samples << ")";
    return {FitStatus::too_few_samples, s.str()};
  }
  for (int j = 0; j < n; ++j) {
    const std::span<const double> y = e.y_m[static_cast<std::size_t>(j)];
    for (std::size_t t = 0; t < y.size(); ++t) {
      if (std::isfinite(y[t]) && std::abs(y[t]) <= kFitMaxAbsPosition_m) continue;
      std::ostringstream s;
      s << experiment_label(k, e.axis) << ": sample " << t << " of " << axis_name(j);
      if (!std::isfinite(y[t])) {
        s << " is not finite (" << y[t] << ")";
        return {FitStatus::non_finite_data, s.str()};
      }
      s << " is " << y[t] << " m, beyond the sanity bound +-" << kFitMaxAbsPosition_m << " m (metres?)";
      return {FitStatus::out_of_range, s.str()};
    }
  }
  const std::span<const double> x = e.y_m[moved];
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  if (!(*hi - *lo >= options.min_travel_m)) {
    std::ostringstream s;
    s << axis_name(e.axis) << " spans " << (*hi - *lo) << " m in " << experiment_label(k, e.axis) << " (< "
      << options.min_travel_m << " m): too little travel to tell its coupling from the sensors' noise";
    return {FitStatus::constant_input, s.str()};
  }
  return {};
}

struct Line {
  double slope = 0.0;           // [-]
  double standard_error = 0.0;  // [-] of the slope
  double residual_rms_m = 0.0;
};

// y = slope x + offset by least squares (centred sums: positions of ~1e-6 m square to ~1e-12 m^2
// without cancellation). x spans > 0 and there are >= 3 samples (checked).
Line fit_line(std::span<const double> x, std::span<const double> y) {
  const double count = static_cast<double>(x.size());
  double sx = 0.0, sy = 0.0;
  for (std::size_t t = 0; t < x.size(); ++t) sx += x[t], sy += y[t];
  const double mx = sx / count, my = sy / count;
  double sxx = 0.0, sxy = 0.0;
  for (std::size_t t = 0; t < x.size(); ++t) sxx += (x[t] - mx) * (x[t] - mx), sxy += (x[t] - mx) * (y[t] - my);
  Line line;
  line.slope = sxy / sxx;
  double ss = 0.0;
  for (std::size_t t = 0; t < x.size(); ++t) {
    const double e = y[t] - my - line.slope * (x[t] - mx);
    ss += e * e;
  }
  line.standard_error = std::sqrt(ss / (count - 2.0) / sxx);
  line.residual_rms_m = std::sqrt(ss / count);
  return line;
}

}  // namespace

CouplingFitResult fit_coupling(std::span<const AxisExcitation> experiments, const CouplingFitOptions& options) {
  options.validate();
  const int n = options.axes;
  CouplingFitResult r;
  r.coupling = AxisCoupling::identity(n);

  std::array<int, kMaxAxes> moved_by{};
  if (FitCheck c = check_experiment_axes(experiments, options, &moved_by); !c.ok()) {
    return with_status(std::move(r), c.status, c.reason);
  }
  for (std::size_t k = 0; k < experiments.size(); ++k) {
    if (FitCheck c = check_experiment_samples(experiments[k], k, options); !c.ok()) {
      return with_status(std::move(r), c.status, c.reason);
    }
  }

  for (int i = 0; i < n; ++i) {
    const int k = moved_by[static_cast<std::size_t>(i)];
    r.excited[static_cast<std::size_t>(i)] = k >= 0;
    for (int j = 0; j < n; ++j) {
      if (j == i) continue;
      if (k < 0) {  // allowed unexcited axis: its column assumed uncoupled
        r.estimate(j, i) = 0.0;
        r.standard_error(j, i) = kNaN;
        r.line_residual_rms_m(j, i) = kNaN;
        continue;
      }
      const AxisExcitation& e = experiments[static_cast<std::size_t>(k)];
      const Line line = fit_line(e.y_m[static_cast<std::size_t>(i)], e.y_m[static_cast<std::size_t>(j)]);
      r.estimate(j, i) = line.slope;
      r.standard_error(j, i) = line.standard_error;
      r.line_residual_rms_m(j, i) = line.residual_rms_m;
      r.residual_rms_m = std::max(r.residual_rms_m, line.residual_rms_m);
    }
  }
  for (const AxisExcitation& e : experiments) r.samples_used += e.y_m[static_cast<std::size_t>(e.axis)].size();

  try {
    r.coupling = AxisCoupling(n, r.estimate);
  } catch (const ParameterError& e) {
    const std::string reason = std::string("the fitted coupling is refused: ") + e.what();
    return with_status(std::move(r), FitStatus::out_of_range, reason);
  }
  return with_status(std::move(r), FitStatus::ok);
}

}  // namespace hystloop
