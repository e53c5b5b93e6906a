#include "path_figures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numbers>

#include "core/errors.hpp"
#include "models/axis_coupling.hpp"

namespace hystloop::report {

namespace {

// Ticks this close to a path's start or end are left out of the start's fit: the printed start
// is within 50 µs of the true one, and before the start the reference is the approach.
constexpr double kFitMarginS = 1e-3;
// Ticks read around a path beyond its measured loop time (for the fit and a tick's rounding).
constexpr double kReadMarginS = 0.01;
// The step of the reference's numerical derivative in the fit [s]: a raster's straight parts are
// linear, and its corners (over a millisecond) and a Lissajous sine are smooth at this scale.
constexpr double kDerivativeStepS = 1e-6;
// The compensator keeps a verdict in its detail for 10 s.
constexpr std::int64_t kVerdictHeldUs = 11'000'000;

// (std::get_if rather than std::visit, which may throw: a path is always one of the two.)
double start_of(const LoggedPath& p) noexcept {
  if (const auto* r = std::get_if<RasterSpec>(&p.path)) return r->start_s;
  const auto* l = std::get_if<LissajousSpec>(&p.path);
  return l != nullptr ? l->start_s : 0.0;
}
void set_start(LoggedPath& p, double start_s) noexcept {
  if (auto* r = std::get_if<RasterSpec>(&p.path)) r->start_s = start_s;
  if (auto* l = std::get_if<LissajousSpec>(&p.path)) l->start_s = start_s;
}
// What is measured: a raster's lines (corners included, not the settle), a Lissajous figure's duration.
double measured_duration_s(const LoggedPath& p) noexcept {
  if (const auto* r = std::get_if<RasterSpec>(&p.path)) return r->lines / r->line_rate_hz;
  const auto* l = std::get_if<LissajousSpec>(&p.path);
  return l != nullptr ? l->duration_s : 0.0;
}

// "from loop time A s to B s" in the compensator's verdict: A.
std::optional<double> printed_start(const std::string& verdict) {
  static const std::string key = "from loop time ";
  const std::size_t at = verdict.find(key);
  if (at == std::string::npos) return std::nullopt;
  const char* from = verdict.c_str() + at + key.size();
  char* end = nullptr;
  const double v = std::strtod(from, &end);
  if (end == from || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::string um_text(double m) { return number_text(m * 1e6, 4) + " µm"; }

// The first tick at or after loop time t. A time within a millionth of a tick of one is that
// tick's: the compensator computes a path's start as ticks x dt + blend, which lands a rounding
// off the tick it means (1.0950000000000002 s for tick 10950).
std::int64_t first_tick_from(double t_s, double dt_s) noexcept {
  return static_cast<std::int64_t>(std::ceil(t_s / dt_s - 1e-6));
}

// The ticks of [from, to) of loop time (first_tick_from), in seq order.
std::vector<const PathTick*> ticks_between(std::span<const PathTick> ticks, double from_s, double to_s) {
  std::vector<const PathTick*> out;
  for (const PathTick& t : ticks) {
    if (t.seq >= first_tick_from(from_s, t.dt_s) && t.seq < first_tick_from(to_s, t.dt_s)) out.push_back(&t);
  }
  std::stable_sort(out.begin(), out.end(), [](const PathTick* a, const PathTick* b) { return a->seq < b->seq; });
  return out;
}

}  // namespace

const char* to_string(PathVerdict verdict) noexcept {
  switch (verdict) {
    case PathVerdict::kTaken: return "taken";
    case PathVerdict::kRefused: return "refused";
    default: return "no verdict";
  }
}

const char* to_string(PositionSource source) noexcept {
  return source == PositionSource::kTrue ? "true (HX_SIM_TRUTH)" : "measured (y_m)";
}

std::string PathFigures::label() const {
  std::string out;
  if (const RasterSpec* r = raster()) {
    out = "raster v" + std::to_string(path.version) + ": " + std::to_string(r->lines) + " lines of " +
          um_text(r->width_m) + " x " + um_text(r->height_m) + " at " + number_text(r->line_rate_hz, 4) + " lines/s (" +
          std::string(axis_name(r->fast_axis)) + " fast, " + std::string(axis_name(r->slow_axis)) + " slow, " +
          (r->slow_mode == SlowMode::kRamp ? "ramp, " : "steps, ");
  } else {
    const auto& l = std::get<LissajousSpec>(path.path);
    out = "Lissajous v" + std::to_string(path.version) + ":";
    for (std::size_t a = 0; a < kScanAxes; ++a) {
      if (!(l.amplitude_m[a] > 0.0)) continue;
      out += " " + std::string(axis_name(static_cast<int>(a))) + " " + um_text(l.amplitude_m[a]) + " " +
             number_text(l.frequency_hz[a], 4) + " Hz,";
    }
    out += " " + number_text(l.duration_s, 4) + " s (";
  }
  return out + (path.decouple ? "decoupled)" : "not decoupled)");
}

AxisPositions path_reference(const LoggedPath& path, double t_s) noexcept {
  if (const auto* r = std::get_if<RasterSpec>(&path.path)) return evaluate(*r, t_s);
  if (const auto* l = std::get_if<LissajousSpec>(&path.path)) return evaluate(*l, t_s);
  return {};
}

std::vector<PathFigures> decide_paths(const PathEvents& events, std::int64_t time_zero_utime) {
  std::vector<PathFigures> out;
  for (const LoggedPath& p : events.paths) {
    PathFigures f;
    f.path = p;
    f.sent_s = static_cast<double>(p.recv_utime - time_zero_utime) * 1e-6;
    const auto& reports = events.compensator;
    std::size_t decided = reports.size();
    bool counted_taken = false;  // trajectory_version = V, the detail with the loop time not seen yet
    for (std::size_t i = 0; i < reports.size(); ++i) {
      const ScanCompensatorStatus& s = reports[i];
      if (s.recv_utime < p.recv_utime) continue;
      if (counted_taken && s.recv_utime > p.recv_utime + kVerdictHeldUs) break;
      if (std::string taken = verdict_text(s.detail, p.version, "taken"); !taken.empty()) {
        f.verdict = PathVerdict::kTaken;
        f.verdict_text = std::move(taken);
        decided = i;
        break;
      }
      std::string refused = verdict_text(s.detail, p.version, "refused");
      if (!refused.empty() || s.trajectory_refused_version == p.version) {
        f.verdict = PathVerdict::kRefused;
        f.verdict_text = refused.empty() ? "(the reason is not in the log)" : std::move(refused);
        decided = i;
        break;
      }
      counted_taken = counted_taken || s.trajectory_version == p.version;
    }
    if (f.verdict == PathVerdict::kRefused) {
      f.skipped = "refused by the compensator: " + f.verdict_text;
    } else if (f.verdict == PathVerdict::kNone) {
      f.skipped = counted_taken ? "taken (trajectory_version), but no compensator report in the log says from which "
                                  "loop time"
                                : "no verdict of the compensator in the log";
    } else if (!(f.printed_start_s = printed_start(f.verdict_text))) {
      f.skipped = "the compensator's verdict names no loop time: " + f.verdict_text;
    }
    if (f.measured()) {
      set_start(f.path, *f.printed_start_s);
      // The path runs until the compensator reports another trajectory as its own.
      for (std::size_t i = decided + 1; i < reports.size(); ++i) {
        if (reports[i].trajectory_version && *reports[i].trajectory_version != p.version) {
          f.replaced_utime = reports[i].recv_utime;
          break;
        }
      }
    }
    out.push_back(std::move(f));
  }
  return out;
}

std::vector<LoopWindow> read_windows(const std::vector<PathFigures>& paths) {
  std::vector<LoopWindow> out;
  for (const PathFigures& f : paths) {
    if (!f.measured()) continue;
    const double start = start_of(f.path);
    out.push_back({start - kReadMarginS, start + measured_duration_s(f.path) + kReadMarginS});
  }
  return out;
}

std::optional<double> raster_corner_from_reference(const RasterSpec& spec, std::span<const PathTick> ticks) {
  const auto fast = static_cast<std::size_t>(spec.fast_axis);
  const double line_s = 1.0 / spec.line_rate_hz;
  std::vector<double> speeds;  // per line, |slope| of a least-squares line through its middle
  std::vector<std::pair<double, double>> points;
  for (int line = 0; line < spec.lines; ++line) {
    const double mid_s = spec.start_s + (line + 0.5) * line_s;
    points.clear();
    for (const PathTick& t : ticks) {
      if (std::abs(t.t_s() - mid_s) <= 0.1 * line_s && fast < static_cast<std::size_t>(t.axes) &&
          std::isfinite(t.y_ref_m[fast])) {
        points.emplace_back(t.t_s() - mid_s, t.y_ref_m[fast]);
      }
    }
    if (points.size() < 3) continue;
    double mean_t = 0.0, mean_y = 0.0;
    for (const auto& [t, y] : points) mean_t += t, mean_y += y;
    mean_t /= static_cast<double>(points.size());
    mean_y /= static_cast<double>(points.size());
    double stt = 0.0, sty = 0.0;
    for (const auto& [t, y] : points) stt += (t - mean_t) * (t - mean_t), sty += (t - mean_t) * (y - mean_y);
    if (stt > 0.0) speeds.push_back(std::abs(sty / stt));
  }
  if (speeds.empty()) return std::nullopt;
  // The median: a line whose middle a stall or a restart touched does not move it.
  std::nth_element(speeds.begin(), speeds.begin() + static_cast<std::ptrdiff_t>(speeds.size() / 2), speeds.end());
  const double v = speeds[speeds.size() / 2];
  if (!(v > 0.0)) return std::nullopt;
  const double corner_s = (line_s - spec.width_m / v) / (1.0 - 2.0 / std::numbers::pi);
  // A corner reaching past 0.8 of a line leaves no straight part in the middle measured.
  if (!(corner_s > -1e-9 * line_s) || !(corner_s < 0.8 * line_s)) return std::nullopt;
  return std::max(corner_s, 0.0);
}

std::optional<double> fit_start(const LoggedPath& path, std::span<const PathTick> ticks) {
  LoggedPath p = path;
  double start = start_of(p);
  const double duration = measured_duration_s(p);
  for (int iteration = 0; iteration < 4; ++iteration) {
    set_start(p, start);
    // y_ref(t) = f(t - s_true) ~ f(t - s) - f'(t - s) (s_true - s): one least-squares step on s.
    double num = 0.0, den = 0.0;
    for (const PathTick& t : ticks) {
      const double tt = t.t_s();
      if (t.safe || tt < start + kFitMarginS || tt > start + duration - kFitMarginS) continue;
      const AxisPositions r = path_reference(p, tt);
      const AxisPositions ahead = path_reference(p, tt + kDerivativeStepS);
      const AxisPositions behind = path_reference(p, tt - kDerivativeStepS);
      for (std::size_t a = 0; a < static_cast<std::size_t>(t.axes); ++a) {
        if (!std::isfinite(t.y_ref_m[a])) continue;
        const double slope = (ahead[a] - behind[a]) / (2.0 * kDerivativeStepS);
        num += slope * (r[a] - t.y_ref_m[a]);
        den += slope * slope;
      }
    }
    if (!(den > 0.0)) return std::nullopt;
    const double step = num / den;
    start += step;
    if (std::abs(step) < 1e-13) break;
  }
  return start;
}

void measure_path(PathFigures& f, std::span<const PathTick> all) {
  if (!f.measured()) return;
  const double printed = start_of(f.path);
  const double duration = measured_duration_s(f.path);
  // This path's ticks, received before another trajectory took over.
  std::vector<PathTick> ticks;
  for (const PathTick& t : all) {
    if (t.t_s() < printed - kReadMarginS || t.t_s() > printed + duration + kReadMarginS) continue;
    if (f.replaced_utime && t.recv_utime >= *f.replaced_utime) {
      f.interrupted = f.interrupted || t.t_s() < printed + duration;
      continue;
    }
    ticks.push_back(t);
    f.axes = std::max(f.axes, t.axes);
  }
  if (ticks.empty()) {
    f.skipped = "no sensor tick of its loop time in the log";
    return;
  }
  // Every axis the path moves must be in the blocks.
  int needed = 1;
  if (const RasterSpec* r = f.raster()) {
    needed = std::max(r->fast_axis, r->slow_axis) + 1;
  } else {
    const auto& l = std::get<LissajousSpec>(f.path.path);
    for (std::size_t a = 0; a < kScanAxes; ++a) {
      if (l.amplitude_m[a] > 0.0) needed = static_cast<int>(a) + 1;
    }
  }
  if (needed > f.axes) {
    f.skipped = "the path moves " + std::string(axis_name(needed - 1)) + ", but the log's sensor blocks carry " +
                std::to_string(f.axes) + (f.axes == 1 ? " axis" : " axes");
    return;
  }
  if (auto* r = std::get_if<RasterSpec>(&f.path.path)) {
    if (r->corner_s > 0.0) {
      f.corner_source = "sent";
    } else if (const auto corner = raster_corner_from_reference(*r, ticks)) {
      r->corner_s = *corner;
      f.corner_source = "the compensator's choice, found from the logged reference's speed";
    } else {
      f.skipped = "its corners were the compensator's choice and the logged reference does not give them";
      return;
    }
  }
  try {
    std::visit([](const auto& spec) { spec.validate(); }, f.path.path);
  } catch (const ParameterError& e) {
    f.skipped = std::string("the path as found is not valid: ") + e.what();
    return;
  }
  if (const auto start = fit_start(f.path, ticks)) set_start(f.path, *start);

  const double dt_s = ticks.front().dt_s;
  f.from_s = start_of(f.path);
  f.to_s = f.from_s + duration;
  const std::vector<const PathTick*> window = ticks_between(ticks, f.from_s, f.to_s);
  if (f.interrupted) {
    const double last_s = window.empty() ? f.from_s : window.back()->t_s() + dt_s;
    f.to_s = std::min(f.to_s, last_s);
  }
  f.expected_ticks = static_cast<std::size_t>(
      std::max<std::int64_t>(0, first_tick_from(f.to_s, dt_s) - first_tick_from(f.from_s, dt_s)));
  const bool truth =
      std::any_of(window.begin(), window.end(), [](const PathTick* t) { return std::isfinite(t->y_true_m[0]); });
  f.position = truth ? PositionSource::kTrue : PositionSource::kMeasured;

  const auto axes = static_cast<std::size_t>(f.axes);
  std::vector<double> sum_sq(axes, 0.0), max_abs(axes, 0.0), mismatch(axes, 0.0);
  std::vector<std::size_t> reference_ticks(axes, 0);
  for (const PathTick* t : window) {
    if (t->safe) {
      ++f.safe_ticks;
      continue;
    }
    const AxisPositions& position = truth ? t->y_true_m : t->y_m;
    // Counted missing below: no true position, or a block of fewer axes (a restarted bridge).
    if (!std::isfinite(position[0]) || t->axes < f.axes) continue;
    const AxisPositions r = path_reference(f.path, t->t_s());
    f.t_s.push_back(t->t_s());
    for (std::size_t a = 0; a < axes; ++a) {
      const double e = r[a] - position[a];
      f.error_m[a].push_back(e);
      sum_sq[a] += e * e;
      max_abs[a] = std::max(max_abs[a], std::abs(e));
      if (std::isfinite(t->y_ref_m[a])) {
        ++reference_ticks[a];
        mismatch[a] = std::max(mismatch[a], std::abs(t->y_ref_m[a] - r[a]));
      }
    }
  }
  const std::size_t measured = f.t_s.size();
  f.missing_ticks = f.expected_ticks - std::min(f.expected_ticks, measured + f.safe_ticks);
  for (std::size_t a = 0; a < axes; ++a) {
    PathAxisFigures x;
    x.axis = static_cast<int>(a);
    if (const RasterSpec* r = f.raster()) {
      x.role = x.axis == r->fast_axis ? "fast" : x.axis == r->slow_axis ? "slow" : "holds";
    } else {
      x.role = std::get<LissajousSpec>(f.path.path).amplitude_m[a] > 0.0 ? "moves" : "holds";
    }
    x.ticks = measured;
    if (measured > 0) {
      x.rms_m = std::sqrt(sum_sq[a] / static_cast<double>(measured));
      x.max_abs_m = max_abs[a];
    }
    x.reference_ticks = reference_ticks[a];
    if (reference_ticks[a] > 0) x.reference_mismatch_m = mismatch[a];
    f.per_axis.push_back(x);
  }
}

}  // namespace hystloop::report
