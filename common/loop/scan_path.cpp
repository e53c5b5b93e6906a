#include "loop/scan_path.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "core/errors.hpp"

namespace hystloop {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string got(double v, const char* unit) { return " (got " + number_text(v) + " " + unit + ")"; }

void finite_in(const std::string& field, double v, const char* unit) {
  if (!std::isfinite(v)) throw ParameterError(field, std::string("must be a finite number of ") + unit + got(v, unit));
}

void positive_in(const std::string& field, double v, const char* unit) {
  finite_in(field, v, unit);
  if (!(v > 0.0)) throw ParameterError(field, std::string("must be > 0 ") + unit + got(v, unit));
}

void non_negative_in(const std::string& field, double v, const char* unit) {
  finite_in(field, v, unit);
  if (v < 0.0) throw ParameterError(field, std::string("must be >= 0 ") + unit + got(v, unit));
}

bool valid_axis(int axis) noexcept { return axis >= 0 && axis < kMaxAxes; }

void require_axis(const std::string& field, int axis) {
  if (!valid_axis(axis)) {
    throw ParameterError(field, "must be 0 (x), 1 (y) or 2 (z) (got " + std::to_string(axis) + ")");
  }
}

std::size_t index(int axis) noexcept { return static_cast<std::size_t>(axis); }

// The usable parts of evaluate(): an unvalidated spec must not index out of range, divide by 0 or
// convert a NaN line number to int (an infinite line rate gives 0 * inf).
bool evaluable(const RasterSpec& s) noexcept {
  return valid_axis(s.fast_axis) && valid_axis(s.slow_axis) && s.fast_axis != s.slow_axis && s.lines >= 2 &&
         s.lines <= RasterSpec::kMaxLines && s.line_rate_hz > 0.0 && std::isfinite(s.line_rate_hz);
}

double lines_s(const RasterSpec& s) noexcept { return s.lines / s.line_rate_hz; }

// The slow axis relative to its centre at tau (clamped to the lines).
double slow_offset_m(const RasterSpec& s, double tau_s) noexcept {
  const double total_s = lines_s(s);
  const double half_m = 0.5 * s.height_m;
  if (!(tau_s > 0.0)) return -half_m;
  if (!(tau_s < total_s)) return half_m;
  if (s.slow_mode == SlowMode::kRamp) {
    // Velocity along a half cosine up to the slope over the first half corner and down over the
    // last: s (1 - cos(pi tau / hc)) / 2, whose integral is s (tau - hc sin(pi tau / hc) / pi) / 2.
    const double hc = 0.5 * std::max(0.0, s.corner_s);
    const double slope = s.height_m / (total_s - hc);  // [m/s]
    auto speeding = [&](double u) { return hc > 0.0 ? 0.5 * slope * (u - hc * std::sin(kPi * u / hc) / kPi) : 0.0; };
    if (tau_s < hc) return -half_m + speeding(tau_s);
    if (tau_s > total_s - hc) return half_m - speeding(total_s - tau_s);
    return -half_m + slope * (tau_s - 0.5 * hc);
  }
  // Steps: one line spacing within each corner between two lines, along a cycloid
  // u - sin(2 pi u) / (2 pi) (velocity 1 - cos(2 pi u), 0 at both ends of the corner).
  const double spacing_m = s.height_m / (s.lines - 1);
  const double boundary = std::round(tau_s * s.line_rate_hz);  // the nearest corner's line boundary
  const double from_corner_s = tau_s - boundary / s.line_rate_hz;
  if (boundary >= 1.0 && boundary <= s.lines - 1 && s.corner_s > 0.0 && std::abs(from_corner_s) < 0.5 * s.corner_s) {
    const double u = from_corner_s / s.corner_s + 0.5;  // [0, 1) through the corner
    const double step = u - std::sin(2.0 * kPi * u) / (2.0 * kPi);
    return -half_m + (boundary - 1.0 + step) * spacing_m;
  }
  const double line = std::min(std::floor(tau_s * s.line_rate_hz), static_cast<double>(s.lines - 1));
  return -half_m + line * spacing_m;
}

// Within [0, lines / line_rate_hz]: before, the raster holds its start; after, its end.
double clamped_tau_s(const RasterSpec& s, double t_s) noexcept { return std::clamp(t_s - s.start_s, 0.0, lines_s(s)); }

}  // namespace

void RasterSpec::validate() const {
  require_axis("raster.fast_axis", fast_axis);
  require_axis("raster.slow_axis", slow_axis);
  if (slow_axis == fast_axis) {
    throw ParameterError("raster.slow_axis",
                         "must differ from raster.fast_axis (both " + std::string(axis_name(fast_axis)) + ")");
  }
  positive_in("raster.width_m", width_m, "m");
  non_negative_in("raster.height_m", height_m, "m");
  if (lines < 2 || lines > kMaxLines) {
    throw ParameterError("raster.lines",
                         "must be in [2, " + std::to_string(kMaxLines) + "] (got " + std::to_string(lines) + ")");
  }
  positive_in("raster.line_rate_hz", line_rate_hz, "Hz");
  if (!std::isfinite(lines / line_rate_hz)) {
    throw ParameterError("raster.line_rate_hz", "too low: the lines would never end" + got(line_rate_hz, "Hz"));
  }
  non_negative_in("raster.corner_s", corner_s, "s");
  if (!(corner_s < 1.0 / line_rate_hz)) {
    throw ParameterError("raster.corner_s", "must be below one line's duration (" + number_text(1.0 / line_rate_hz) +
                                                " s at " + number_text(line_rate_hz) + " Hz)" + got(corner_s, "s"));
  }
  if (slow_mode == SlowMode::kSteps) {
    if (!(corner_s > 0.0)) {
      throw ParameterError("raster.corner_s",
                           "must be > 0 s with slow_mode steps: the slow axis moves within the "
                           "corners, and without one it would step" +
                               got(corner_s, "s"));
    }
  } else if (slow_mode != SlowMode::kRamp) {
    throw ParameterError("raster.slow_mode",
                         "must be steps or ramp (got " + std::to_string(static_cast<int>(slow_mode)) + ")");
  }
  for (std::size_t i = 0; i < kScanAxes; ++i) {
    if (!std::isfinite(centre_m[i])) {
      throw ParameterError("raster.centre_m", "axis " + std::string(axis_name(static_cast<int>(i))) +
                                                  ": must be a finite number of m" + got(centre_m[i], "m"));
    }
  }
  non_negative_in("raster.settle_s", settle_s, "s");
  finite_in("raster.start_s", start_s, "s");
}

double raster_duration_s(const RasterSpec& spec) noexcept { return lines_s(spec) + spec.settle_s; }

TrajectorySpec raster_fast_trajectory(const RasterSpec& spec) noexcept {
  TrajectorySpec t;
  t.shape = TrajectoryShape::kTriangle;
  t.amplitude_m = 0.5 * spec.width_m;
  t.offset_m = valid_axis(spec.fast_axis) ? spec.centre_m[index(spec.fast_axis)] : 0.0;
  t.frequency_hz = 0.5 * spec.line_rate_hz;
  t.phase_rad = 1.5 * kPi;  // three quarters of a period: the trough, so line 0 rises from it
  t.corner_s = spec.corner_s;
  t.start_s = spec.start_s;
  t.hold_m = t.offset_m - t.amplitude_m;
  return t;
}

namespace {
// evaluate() with the fast triangle built once (ScanShare keeps it).
AxisPositions raster_at(const RasterSpec& spec, const TrajectorySpec& fast, double t_s) noexcept {
  AxisPositions y = spec.centre_m;
  if (!evaluable(spec)) return y;
  const double tau_s = clamped_tau_s(spec, t_s);
  y[index(spec.fast_axis)] = evaluate_shape(fast, tau_s);
  y[index(spec.slow_axis)] += slow_offset_m(spec, tau_s);
  return y;
}
}  // namespace

AxisPositions evaluate(const RasterSpec& spec, double t_s) noexcept {
  return raster_at(spec, raster_fast_trajectory(spec), t_s);
}

RasterPoint raster_point(const RasterSpec& spec, double t_s) noexcept {
  RasterPoint p;
  if (!evaluable(spec)) return p;
  const double tau_s = t_s - spec.start_s;
  const double total_s = lines_s(spec);
  if (!(tau_s >= 0.0)) return p;
  const bool ended = !(tau_s < total_s);
  const double lines_in = std::floor(std::min(tau_s, total_s) * spec.line_rate_hz);
  p.line = static_cast<int>(std::min(lines_in, static_cast<double>(spec.lines - 1)));
  p.direction = p.line % 2 == 0 ? 1 : -1;
  if (ended) {
    p.along = 1.0;
    return p;
  }
  const double fast_m = evaluate_shape(raster_fast_trajectory(spec), tau_s);
  const double from_low = (fast_m - (spec.centre_m[index(spec.fast_axis)] - 0.5 * spec.width_m)) / spec.width_m;
  p.along = std::clamp(p.direction > 0 ? from_low : 1.0 - from_low, 0.0, 1.0);
  const double line_start_s = p.line / spec.line_rate_hz;
  const double half_corner_s = 0.5 * spec.corner_s;
  p.on_straight =
      tau_s >= line_start_s + half_corner_s && tau_s <= line_start_s + 1.0 / spec.line_rate_hz - half_corner_s;
  return p;
}

std::array<AxisPeaks, kScanAxes> raster_peaks(const RasterSpec& spec) noexcept {
  std::array<AxisPeaks, kScanAxes> peaks{};
  for (std::size_t i = 0; i < kScanAxes; ++i) peaks[i].min_m = peaks[i].max_m = spec.centre_m[i];
  if (!evaluable(spec)) return peaks;
  AxisPeaks& fast = peaks[index(spec.fast_axis)];
  fast.min_m -= 0.5 * spec.width_m;
  fast.max_m += 0.5 * spec.width_m;
  fast.derivatives = peak_derivatives(raster_fast_trajectory(spec));

  AxisPeaks& slow = peaks[index(spec.slow_axis)];
  slow.min_m -= 0.5 * spec.height_m;
  slow.max_m += 0.5 * spec.height_m;
  if (spec.height_m == 0.0) return peaks;
  const double c = spec.corner_s;
  ShapePeaks& d = slow.derivatives;
  if (spec.slow_mode == SlowMode::kRamp) {
    const double slope = spec.height_m / (lines_s(spec) - 0.5 * std::max(0.0, c));
    d.velocity_m_per_s = slope;
    d.acceleration_m_per_s2 = c > 0.0 ? slope * kPi / c : kInf;
    d.jerk_m_per_s3 = c > 0.0 ? 2.0 * slope * kPi * kPi / (c * c) : kInf;
  } else {
    const double spacing_m = spec.height_m / (spec.lines - 1);
    d.velocity_m_per_s = c > 0.0 ? 2.0 * spacing_m / c : kInf;
    d.acceleration_m_per_s2 = c > 0.0 ? 2.0 * kPi * spacing_m / (c * c) : kInf;
    d.jerk_m_per_s3 = c > 0.0 ? 4.0 * kPi * kPi * spacing_m / (c * c * c) : kInf;
  }
  return peaks;
}

void LissajousSpec::validate() const {
  bool moving = false;
  for (std::size_t i = 0; i < kScanAxes; ++i) {
    const std::string axis = "axis " + std::string(axis_name(static_cast<int>(i))) + ": ";
    if (!(std::isfinite(amplitude_m[i]) && amplitude_m[i] >= 0.0)) {
      throw ParameterError("lissajous.amplitude_m", axis + "must be a finite number >= 0 m" + got(amplitude_m[i], "m"));
    }
    if (amplitude_m[i] > 0.0) {
      moving = true;
      if (!(std::isfinite(frequency_hz[i]) && frequency_hz[i] > 0.0)) {
        throw ParameterError("lissajous.frequency_hz",
                             axis + "must be > 0 Hz on a moving axis" + got(frequency_hz[i], "Hz"));
      }
    }
    if (!std::isfinite(phase_rad[i])) {
      throw ParameterError("lissajous.phase_rad", axis + "must be a finite number of rad" + got(phase_rad[i], "rad"));
    }
    if (!std::isfinite(centre_m[i])) {
      throw ParameterError("lissajous.centre_m", axis + "must be a finite number of m" + got(centre_m[i], "m"));
    }
  }
  if (!moving) throw ParameterError("lissajous.amplitude_m", "at least one axis must have an amplitude > 0 m");
  positive_in("lissajous.duration_s", duration_s, "s");
  finite_in("lissajous.start_s", start_s, "s");
}

TrajectorySpec lissajous_axis_trajectory(const LissajousSpec& spec, int axis) noexcept {
  TrajectorySpec t;
  t.start_s = spec.start_s;
  if (!valid_axis(axis)) return t;
  const std::size_t i = index(axis);
  t.offset_m = spec.centre_m[i];
  t.hold_m = spec.centre_m[i];
  if (!(spec.amplitude_m[i] > 0.0)) return t;  // kHold at the centre
  t.shape = TrajectoryShape::kSine;
  t.amplitude_m = spec.amplitude_m[i];
  t.frequency_hz = spec.frequency_hz[i];
  t.phase_rad = spec.phase_rad[i];
  return t;
}

namespace {
double lissajous_tau_s(const LissajousSpec& spec, double t_s) noexcept {
  return std::clamp(t_s - spec.start_s, 0.0, std::max(0.0, spec.duration_s));
}
}  // namespace

AxisPositions evaluate(const LissajousSpec& spec, double t_s) noexcept {
  const double tau_s = lissajous_tau_s(spec, t_s);
  AxisPositions y{};
  for (int i = 0; i < kMaxAxes; ++i) y[index(i)] = evaluate_shape(lissajous_axis_trajectory(spec, i), tau_s);
  return y;
}

std::array<AxisPeaks, kScanAxes> lissajous_peaks(const LissajousSpec& spec) noexcept {
  std::array<AxisPeaks, kScanAxes> peaks{};
  for (int i = 0; i < kMaxAxes; ++i) {
    const TrajectorySpec t = lissajous_axis_trajectory(spec, i);
    AxisPeaks& p = peaks[index(i)];
    p.min_m = t.offset_m - std::abs(t.amplitude_m);
    p.max_m = t.offset_m + std::abs(t.amplitude_m);
    p.derivatives = peak_derivatives(t);
  }
  return peaks;
}

namespace {

void validate_row(int axis, const AxisVector& row) {
  require_axis("scan.axis", axis);
  for (int j = 0; j < kMaxAxes; ++j) {
    if (!std::isfinite(row[j])) {
      throw ParameterError("scan.row",
                           "the weight of axis " + std::string(axis_name(j)) + " must be finite" + got(row[j], "m/m"));
    }
  }
  if (row[axis] == 0.0) {
    throw ParameterError("scan.row", "must weigh axis " + std::string(axis_name(axis)) +
                                         "'s own reference (its weight is 0: not a row of an inverse coupling)");
  }
}

}  // namespace

ScanShare::ScanShare(const RasterSpec& raster, int axis, const AxisVector& row)
    : path_(raster), axis_(axis), row_(row), start_s_(raster.start_s) {
  raster.validate();
  validate_row(axis, row);
  shapes_[0] = raster_fast_trajectory(raster);
  end_s_ = raster.start_s + lines_s(raster);
  // Periodic when the share is the fast axis's triangle up to less than kPeriodicShareTolerance_m of
  // anything else: a coupling identified on a real stage has near-zero entries (a fit's 2e-5 of the
  // slow axis's 1 um: 0.02 nm) that must not keep learning off; a share carrying a few per cent of
  // the slow axis's steps is not periodic.
  if (axis == raster.fast_axis) {
    const double off_m = std::abs(row[raster.fast_axis] - 1.0) * raster.width_m +
                         std::abs(row[raster.slow_axis]) * raster.height_m;  // the other axes hold still
    periodic_ = off_m <= kPeriodicShareTolerance_m;
  }
}

ScanShare::ScanShare(const LissajousSpec& lissajous, int axis, const AxisVector& row)
    : path_(lissajous), axis_(axis), row_(row), start_s_(lissajous.start_s) {
  lissajous.validate();
  validate_row(axis, row);
  for (int i = 0; i < kMaxAxes; ++i) shapes_[index(i)] = lissajous_axis_trajectory(lissajous, i);
  end_s_ = lissajous.start_s + lissajous.duration_s;
}

AxisPositions ScanShare::path_at(double t_s) const noexcept {
  if (const auto* raster = std::get_if<RasterSpec>(&path_)) return raster_at(*raster, shapes_[0], t_s);
  AxisPositions y{};
  if (const auto* lissajous = std::get_if<LissajousSpec>(&path_)) {
    const double tau_s = lissajous_tau_s(*lissajous, t_s);
    for (std::size_t i = 0; i < kScanAxes; ++i) y[i] = evaluate_shape(shapes_[i], tau_s);
  }
  return y;
}

ScanShare::Point ScanShare::point(double t_s) const noexcept {
  const AxisPositions r = path_at(t_s);
  Point p;
  p.own_m = r[index(axis_)];
  for (std::size_t j = 0; j < kScanAxes; ++j) {
    if (row_[static_cast<Eigen::Index>(j)] != 0.0) p.share_m += row_[static_cast<Eigen::Index>(j)] * r[j];
  }
  return p;
}

double ScanShare::at(double t_s) const noexcept { return point(t_s).share_m; }

namespace {

// The bound of the header: each term of the stage's inverse at its peak.
VoltageNeed need_from_peaks(const LinearPlant& plant, const AxisPeaks& p) noexcept {
  const double g = plant.gain_m_per_V;
  const ShapePeaks& d = p.derivatives;
  if (!plant.stage) return {p.min_m / g, p.max_m / g, d.velocity_m_per_s / g};
  const double k = plant.stage->k, c = plant.stage->c;
  // 0 * inf would be NaN: a derivative that is 0 contributes nothing.
  auto term = [](double coef, double peak) { return peak == 0.0 ? 0.0 : coef * peak; };
  const double margin_m = term(c / k, d.velocity_m_per_s) + term(1.0 / k, d.acceleration_m_per_s2);
  const double rate_m_per_s =
      d.velocity_m_per_s + term(c / k, d.acceleration_m_per_s2) + term(1.0 / k, d.jerk_m_per_s3);
  return {(p.min_m - margin_m) / g, (p.max_m + margin_m) / g, rate_m_per_s / g};
}

void validate_actuators(std::span<const AxisActuator> actuators) {
  if (actuators.empty() || actuators.size() > kScanAxes) {
    throw ParameterError("actuators", "must be one per axis, 1 to " + std::to_string(kMaxAxes) + " (got " +
                                          std::to_string(actuators.size()) + ")");
  }
  for (std::size_t i = 0; i < actuators.size(); ++i) {
    const std::string prefix(axis_name(static_cast<int>(i)));
    // Their fields are already "plant.gain_m_per_V", "limits.slew_V_per_s": the axis goes in front.
    validate_within(prefix + ".", [&] { actuators[i].plant.validate(); });
    validate_within(prefix + ".", [&] { actuators[i].limits.validate(); });
  }
}

void require_actuated(const std::string& field, int axis, std::size_t n) {
  if (index(axis) >= n) {
    throw ParameterError(field,
                         "axis " + std::string(axis_name(axis)) + " has no actuator (" + std::to_string(n) + " given)");
  }
}

// "[-300, 300] V". Appended piece by piece: GCC 12's -Wrestrict misreads "[" + std::string.
std::string interval_V(double lo_V, double hi_V) {
  std::string out("[");
  out += number_text(lo_V);
  out += ", ";
  out += number_text(hi_V);
  out += "] V";
  return out;
}

// Fills the verdict from the per-axis needs: the first axis, in axis order, that breaks a limit.
ScanFeasibility verdict(const std::array<VoltageNeed, kScanAxes>& needs, std::span<const AxisActuator> actuators,
                        const std::array<const char*, kScanAxes>& roles) {
  ScanFeasibility v;
  v.needs = needs;
  for (std::size_t i = 0; i < actuators.size(); ++i) {
    const FeedforwardLimits& lim = actuators[i].limits;
    const Limit limit = exceeded_limit(needs[i], lim);
    if (limit == Limit::kNone) continue;
    v.axis = static_cast<int>(i);
    v.limit = limit;
    v.reason = std::string(axis_name(v.axis)) + roles[i] + " exceeds its " + to_string(limit) + " limit: needs ";
    if (limit == Limit::kRange) {
      v.reason += interval_V(needs[i].u_min_V, needs[i].u_max_V) + ", " +
                  interval_V(lim.usable_min_V(), lim.usable_max_V()) + " usable";
    } else {
      v.reason +=
          number_text(needs[i].rate_V_per_s) + " V/s, " + number_text(lim.usable_slew_V_per_s()) + " V/s usable";
    }
    break;
  }
  return v;
}

}  // namespace

ScanFeasibility check_raster_feasible(const RasterSpec& spec, std::span<const AxisActuator> actuators) {
  spec.validate();
  validate_actuators(actuators);
  require_actuated("raster.fast_axis", spec.fast_axis, actuators.size());
  require_actuated("raster.slow_axis", spec.slow_axis, actuators.size());
  const std::array<AxisPeaks, kScanAxes> peaks = raster_peaks(spec);
  std::array<VoltageNeed, kScanAxes> needs{};
  std::array<const char*, kScanAxes> roles{};
  for (std::size_t i = 0; i < actuators.size(); ++i) {
    const LinearPlant& plant = actuators[i].plant;
    if (i == index(spec.fast_axis)) {
      needs[i] = voltage_need(plant, raster_fast_trajectory(spec));
      roles[i] = " (fast axis)";
    } else {
      needs[i] = need_from_peaks(plant, peaks[i]);
      roles[i] = i == index(spec.slow_axis) ? " (slow axis)" : " (holding its centre)";
    }
  }
  return verdict(needs, actuators, roles);
}

ScanFeasibility check_lissajous_feasible(const LissajousSpec& spec, std::span<const AxisActuator> actuators) {
  spec.validate();
  validate_actuators(actuators);
  for (std::size_t i = actuators.size(); i < kScanAxes; ++i) {
    if (spec.amplitude_m[i] > 0.0) require_actuated("lissajous.amplitude_m", static_cast<int>(i), actuators.size());
  }
  std::array<VoltageNeed, kScanAxes> needs{};
  std::array<const char*, kScanAxes> roles{};
  for (std::size_t i = 0; i < actuators.size(); ++i) {
    needs[i] = voltage_need(actuators[i].plant, lissajous_axis_trajectory(spec, static_cast<int>(i)));
    roles[i] = spec.amplitude_m[i] > 0.0 ? "" : " (holding its centre)";
  }
  return verdict(needs, actuators, roles);
}

}  // namespace hystloop
