#include "scan_figures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/errors.hpp"
#include "report_metrics.hpp"
#include "hystloop/sensor_block_t.hpp"

namespace hystloop::report {

namespace {

constexpr std::int32_t kClampFlags = std::int32_t{sensor_block_t::SATURATED} | sensor_block_t::SLEW_LIMITED;

// The compensator's verdict on trajectory `t`: its first report that decides this version.
void find_verdict(const ScanEvents& events, const ScanTrajectory& t, ReferenceFigures& r) {
  bool counters = false;
  for (const auto& s : events.compensator) {
    if (s.recv_utime < t.recv_utime) continue;
    counters = counters || s.trajectory_version.has_value();
    if (s.trajectory_refused_version == t.version) {
      r.verdict = Verdict::kRefused;
      r.verdict_detail = verdict_text(s.detail, t.version, "refused");
      return;
    }
    if (s.trajectory_version == t.version) {
      const bool shaped = s.trajectory_shaped_version == t.version;
      r.verdict = shaped ? Verdict::kShaped : Verdict::kAccepted;
      r.verdict_detail = verdict_text(s.detail, t.version, shaped ? "shaped" : "taken");
      return;
    }
    if (std::max(s.trajectory_version.value_or(0), s.trajectory_refused_version.value_or(0)) > t.version) break;
  }
  r.verdict = Verdict::kUnconfirmed;
  r.verdict_detail = counters ? "no verdict of the compensator in the log"
                              : "the compensator's reports carry no verdicts (an older compensator?)";
}

struct Boundary {
  std::int64_t utime = 0;
  std::optional<std::size_t> trajectory;  // index into events.trajectories
  std::optional<ScanControl::Kind> control;
};

std::vector<Boundary> boundaries(const ScanEvents& events) {
  std::vector<Boundary> out;
  for (std::size_t i = 0; i < events.trajectories.size(); ++i)
    out.push_back({events.trajectories[i].recv_utime, i, {}});
  for (const auto& c : events.controls) out.push_back({c.recv_utime, {}, c.kind});
  std::stable_sort(out.begin(), out.end(), [](const Boundary& a, const Boundary& b) { return a.utime < b.utime; });
  return out;
}

struct Segment {
  std::int64_t start_utime = 0, end_utime = 0;
  double skip_s = 0.0;
  LearningState learning = LearningState::kUnknown;
  // Ended by a DISARM or SHUTDOWN: the safe-state ticks it ends with are the stop's. The report
  // dates a block's ticks back from its arrival, one tick apart, but the bridge runs a block's
  // ticks in a burst (rt.ticks_per_wake), so those of the burst after the stop came in are dated
  // up to a block before the request.
  bool ends_at_stop = false;
};

// The first seq of the run of safe-state ticks that ends the segment, if it ends with one.
std::optional<std::int64_t> trailing_safe_from(const RunData& run, const Segment& seg) {
  std::optional<std::int64_t> from;
  for (const auto& s : run.samples) {
    if (s.recv_utime < seg.start_utime || s.recv_utime >= seg.end_utime) continue;
    if ((s.flags & sensor_block_t::SAFE_STATE) == 0) {
      from.reset();
    } else if (!from) {
      from = s.seq;
    }
  }
  return from;
}

void add_compensator_figures(const ScanEvents& events, const Segment& seg, SegmentFigures& f) {
  const ScanCompensatorStatus* before = nullptr;
  const ScanCompensatorStatus* last = nullptr;
  for (const auto& s : events.compensator) {
    if (s.recv_utime < seg.start_utime) before = &s;
    if (s.recv_utime >= seg.start_utime && s.recv_utime < seg.end_utime) {
      if (before == nullptr) before = &s;
      last = &s;
    }
  }
  if (last == nullptr) return;
  if (last->learning_rms_pm) f.learned_rms_m = static_cast<double>(*last->learning_rms_pm) * 1e-12;
  f.learning_periods = last->learning_periods;
  f.mode = compensator_mode(last->detail);
  if (before != nullptr && before->model_switches && last->model_switches) {
    f.model_switches = std::max<std::int64_t>(0, *last->model_switches - *before->model_switches);
  }
  if (before != nullptr && before->params_swapped && last->params_swapped) {
    f.params_swaps = std::max<std::int64_t>(0, *last->params_swapped - *before->params_swapped);
  }
  if (f.learning == LearningState::kUnknown && last->learning_active) {
    f.learning = *last->learning_active != 0 ? LearningState::kOn : LearningState::kOff;
  }
}

SegmentFigures measure(const RunData& run, const ScanEvents& events, const ScanTrajectory& t, const Segment& seg,
                       double dt_s, const ScanOptions& o) {
  SegmentFigures f;
  f.learning = seg.learning;
  f.start_s = run.t_s(seg.start_utime);
  f.end_s = run.t_s(seg.end_utime);
  f.analysed_from_s = std::min(f.end_s, f.start_s + seg.skip_s);
  f.period_ticks = std::max<std::int64_t>(1, std::llround(1.0 / (t.frequency_hz * dt_s)));
  const double last_from_s = std::max(f.analysed_from_s, f.end_s - o.last_s);

  RmsSum all, last, truth;
  double max_abs = 0.0, max_abs_true = 0.0;
  std::int64_t first_seq = std::numeric_limits<std::int64_t>::max(),
               last_seq = std::numeric_limits<std::int64_t>::min();
  const std::int64_t stop_seq = seg.ends_at_stop
                                    ? trailing_safe_from(run, seg).value_or(std::numeric_limits<std::int64_t>::max())
                                    : std::numeric_limits<std::int64_t>::max();
  for (const auto& s : run.samples) {
    if (s.recv_utime < seg.start_utime || s.recv_utime >= seg.end_utime) continue;
    if (s.seq >= stop_seq) continue;
    ++f.ticks;
    first_seq = std::min(first_seq, s.seq);
    last_seq = std::max(last_seq, s.seq);
    if ((s.flags & kClampFlags) != 0) ++f.clamped_ticks;
    if ((s.flags & sensor_block_t::SATURATED) != 0) ++f.saturated_ticks;
    if ((s.flags & sensor_block_t::SLEW_LIMITED) != 0) ++f.slew_limited_ticks;
    if ((s.flags & sensor_block_t::LATE_COMMAND) != 0) ++f.late_ticks;
    if ((s.flags & sensor_block_t::SAFE_STATE) != 0) ++f.safe_ticks;
    const double t_s = run.t_s(s.recv_utime);
    if (!std::isfinite(s.y_ref_m) || t_s < f.analysed_from_s) continue;
    const double e = s.y_ref_m - s.y_m;
    all.add(e);
    max_abs = std::max(max_abs, std::abs(e));
    if (t_s >= last_from_s) last.add(e);
    if (std::isfinite(s.y_true_m)) {
      const double e_true = s.y_ref_m - s.y_true_m;
      truth.add(e_true);
      max_abs_true = std::max(max_abs_true, std::abs(e_true));
    }
  }
  f.analysed_ticks = all.n;
  f.true_ticks = truth.n;
  f.rms_m = all.rms();
  if (all.n > 0) f.max_abs_m = max_abs;
  if (truth.n > 0 && truth.n == all.n) {  // only over the same ticks as the measured figures
    f.rms_true_m = truth.rms();
    f.max_abs_true_m = max_abs_true;
  }
  f.rms_last_m = last.rms();

  if (f.ticks > 0) {  // complete periods from the segment's first tick, by tick number
    const std::int64_t n = f.period_ticks;
    const auto periods = static_cast<std::size_t>((last_seq - first_seq + 1) / n);
    std::vector<RmsSum> per(periods);
    for (const auto& s : run.samples) {
      if (s.recv_utime < seg.start_utime || s.recv_utime >= seg.end_utime || !std::isfinite(s.y_ref_m)) continue;
      const auto p = static_cast<std::size_t>((s.seq - first_seq) / n);
      if (p < periods) per[p].add(s.y_ref_m - s.y_m);
    }
    for (const auto& p : per) {
      if (static_cast<double>(p.n) >= 0.9 * static_cast<double>(n)) f.period_rms_m.push_back(*p.rms());
    }
    f.periods_to_converge = periods_to_converge(f.period_rms_m, o.converge_factor, o.converge_tail);
    f.tail_median_m = median_of_last(f.period_rms_m, o.converge_tail);
  }
  add_compensator_figures(events, seg, f);
  return f;
}

void keep_longest(std::optional<SegmentFigures>& slot, SegmentFigures f) {
  if (!slot || f.analysed_s() > slot->analysed_s()) slot = std::move(f);
}

}  // namespace

void ScanOptions::validate() const {
  if (!(settle_s >= 0.0) || !std::isfinite(settle_s)) throw ParameterError("--scan-settle", "must be >= 0 [s]");
  if (!(last_s > 0.0) || !std::isfinite(last_s)) throw ParameterError("--scan-last", "must be > 0 [s]");
  if (!(min_analysed_s >= 0.0) || !std::isfinite(min_analysed_s)) {
    throw ParameterError("--scan-min-analysed", "must be >= 0 [s]");
  }
  if (!(converge_factor > 1.0) || !std::isfinite(converge_factor)) {
    throw ParameterError("--scan-converge-factor", "must be > 1");
  }
  if (converge_tail < 1) throw ParameterError("--scan-converge-tail", "must be >= 1 period");
}

const char* to_string(LearningState state) noexcept {
  switch (state) {
    case LearningState::kOff: return "off";
    case LearningState::kOn: return "on";
    default: return "unknown";
  }
}

const char* to_string(Verdict verdict) noexcept {
  switch (verdict) {
    case Verdict::kAccepted: return "accepted";
    case Verdict::kShaped: return "shaped";
    case Verdict::kRefused: return "refused";
    default: return "unconfirmed";
  }
}

std::string ReferenceFigures::label() const {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%s %g µm %g Hz", trajectory.shape.c_str(), trajectory.amplitude_m * 1e6,
                trajectory.frequency_hz);
  std::string out = buf;
  if (trajectory.offset_m != 0.0) {
    std::snprintf(buf, sizeof buf, " offset %g µm", trajectory.offset_m * 1e6);
    out += buf;
  }
  return out;
}

std::size_t ScanResult::refused() const noexcept {
  return static_cast<std::size_t>(std::count_if(
      references.begin(), references.end(), [](const ReferenceFigures& r) { return r.verdict == Verdict::kRefused; }));
}

std::size_t periodic_trajectories(const ScanEvents& events) noexcept {
  return static_cast<std::size_t>(std::count_if(events.trajectories.begin(), events.trajectories.end(),
                                                [](const ScanTrajectory& t) { return t.periodic(); }));
}

std::optional<double> median_of_last(const std::vector<double>& values, std::size_t tail) {
  if (values.empty() || tail == 0) return std::nullopt;
  std::vector<double> v(values.end() - static_cast<std::ptrdiff_t>(std::min(tail, values.size())), values.end());
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::optional<std::size_t> periods_to_converge(const std::vector<double>& rms, double factor, std::size_t tail) {
  if (tail == 0 || rms.size() < tail) return std::nullopt;
  const double bound = factor * *median_of_last(rms, tail);
  std::size_t first = 0;  // the first period of the run that stays within the bound
  for (std::size_t i = 0; i < rms.size(); ++i) {
    if (!(rms[i] <= bound)) first = i + 1;
  }
  if (rms.size() - first < tail) return std::nullopt;  // not settled for a whole tail yet
  return first;
}

ScanResult compute_scan(const RunData& run, const ScanEvents& events, const ScanOptions& o) {
  o.validate();
  ScanResult result;
  result.options = o;
  if (!run.sensor_blocks.empty()) result.dt_s = run.sensor_blocks.front().dt_s;

  // One row per periodic trajectory, in the order sent.
  std::vector<std::optional<std::size_t>> row_of(events.trajectories.size());
  for (std::size_t i = 0; i < events.trajectories.size(); ++i) {
    const ScanTrajectory& t = events.trajectories[i];
    if (!t.periodic()) continue;
    ReferenceFigures r;
    r.trajectory = t;
    r.sent_s = run.t_s(t.recv_utime);
    find_verdict(events, t, r);
    row_of[i] = result.references.size();
    result.references.push_back(std::move(r));
  }
  if (run.samples.empty() || !result.dt_s) return result;

  std::int64_t end_utime = run.samples.front().recv_utime;
  for (const auto& s : run.samples) end_utime = std::max(end_utime, s.recv_utime);

  // Walk the boundaries: what runs (the reference's row, if periodic) and the learning state.
  // Index into events.trajectories of the trajectory taken last (kNone: no reference runs). Not an
  // optional: GCC 12 warns falsely that one captured by the lambda may be used uninitialised.
  constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  std::size_t running = kNone;
  LearningState learning = LearningState::kUnknown;
  Segment seg;
  auto close = [&](std::int64_t until) {
    seg.end_utime = std::min(until, end_utime);
    if (running == kNone || !row_of[running] || seg.end_utime <= seg.start_utime) return;
    SegmentFigures f = measure(run, events, events.trajectories[running], seg, *result.dt_s, o);
    if (f.analysed_s() < o.min_analysed_s) return;
    ReferenceFigures& r = result.references[*row_of[running]];
    if (f.learning == LearningState::kOn) {
      keep_longest(r.on, std::move(f));
    } else if (f.learning == LearningState::kOff) {
      keep_longest(r.off, std::move(f));
    }
  };
  for (const Boundary& b : boundaries(events)) {
    seg.ends_at_stop = b.control == ScanControl::Kind::kStop;
    close(b.utime);
    seg = Segment{b.utime, b.utime, o.settle_s, learning};
    if (b.trajectory) {
      const ReferenceFigures* row = row_of[*b.trajectory] ? &result.references[*row_of[*b.trajectory]] : nullptr;
      if (row != nullptr && row->verdict == Verdict::kRefused) continue;  // the previous reference runs on
      running = *b.trajectory;
      seg.skip_s = events.trajectories[*b.trajectory].blend_s + o.settle_s;
    } else if (b.control) {
      switch (*b.control) {
        case ScanControl::Kind::kLearningOff: learning = LearningState::kOff; break;
        case ScanControl::Kind::kLearningOn: learning = LearningState::kOn; break;
        case ScanControl::Kind::kLearningReset: break;  // starts again, on or off as it was
        case ScanControl::Kind::kMode:  // another feedforward: what follows is not this reference's figure
        case ScanControl::Kind::kExperiment:
        case ScanControl::Kind::kStop: running = kNone; break;
      }
      seg.learning = learning;
    }
  }
  close(end_utime + 1);
  return result;
}

}  // namespace hystloop::report
