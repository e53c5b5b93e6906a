#include "ident/coupling_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <fmt/format.h>
#include <string>
#include <utility>

#include "core/errors.hpp"
#include "ident/fit_checks.hpp"
#include "ident/fit_clock.hpp"
#include "ident/linear_fit.hpp"

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
  return fmt::format("experiment {} ({} moved)", k, axis_name(axis));
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
      return {FitStatus::out_of_range,
              fmt::format("experiment {} moves axis {}, but the fit has {} axes (0..{})", k, axis, n, n - 1)};
    }
    const auto a = static_cast<std::size_t>(axis);
    if ((*moved_by)[a] >= 0) {
      return {FitStatus::size_mismatch,
              fmt::format("axis {} is moved by experiments {} and {}: give one experiment per axis", axis_name(axis),
                          (*moved_by)[a], k)};
    }
    (*moved_by)[a] = static_cast<int>(k);
  }
  if (!options.allow_unexcited_axes) {
    for (int i = 0; i < n; ++i) {
      if ((*moved_by)[static_cast<std::size_t>(i)] < 0) {
        return {FitStatus::too_few_samples,
                fmt::format("no experiment moves axis {}, so its effect on the other axes is unknown (move it, or set "
                            "allow_unexcited_axes to take it as uncoupled)",
                            axis_name(i))};
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
    if (j < n && y.size() != len) {
      return {FitStatus::size_mismatch, fmt::format("{}: {} has {} samples, {} has {}", experiment_label(k, e.axis),
                                                    axis_name(j), y.size(), axis_name(e.axis), len)};
    }
    if (j >= n && !y.empty()) {
      return {FitStatus::size_mismatch, fmt::format("{}: {} has {} samples, but the fit has {} axes",
                                                    experiment_label(k, e.axis), axis_name(j), y.size(), n)};
    }
  }
  if (len < options.min_samples) {
    return {FitStatus::too_few_samples,
            fmt::format("{}: {} samples (need {})", experiment_label(k, e.axis), len, options.min_samples)};
  }
  for (int j = 0; j < n; ++j) {
    const std::span<const double> y = e.y_m[static_cast<std::size_t>(j)];
    for (std::size_t t = 0; t < y.size(); ++t) {
      if (std::isfinite(y[t]) && std::abs(y[t]) <= kFitMaxAbsPosition_m) continue;
      const std::string where = fmt::format("{}: sample {} of {}", experiment_label(k, e.axis), t, axis_name(j));
      if (!std::isfinite(y[t]))
        return {FitStatus::non_finite_data, fmt::format("{} is not finite ({:g})", where, y[t])};
      return {FitStatus::out_of_range, fmt::format("{} is {:g} m, beyond the sanity bound +-{:g} m (metres?)", where,
                                                   y[t], kFitMaxAbsPosition_m)};
    }
  }
  const std::span<const double> x = e.y_m[moved];
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  if (!(*hi - *lo >= options.min_travel_m)) {
    return {
        FitStatus::constant_input,
        fmt::format("{} spans {:g} m in {} (< {:g} m): too little travel to tell its coupling from the sensors' noise",
                    axis_name(e.axis), *hi - *lo, experiment_label(k, e.axis), options.min_travel_m)};
  }
  return {};
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
      const LeastSquaresLine line =
          least_squares_line(e.y_m[static_cast<std::size_t>(i)], e.y_m[static_cast<std::size_t>(j)]);
      r.estimate(j, i) = line.slope;
      r.standard_error(j, i) = line.slope_standard_error;
      r.line_residual_rms_m(j, i) = line.residual_rms;
      r.residual_rms_m = std::max(r.residual_rms_m, line.residual_rms);
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
