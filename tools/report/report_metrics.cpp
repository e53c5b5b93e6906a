#include "report_metrics.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "status_figures.hpp"

namespace hystloop::report {

namespace {

// A SAFE_STATE transition up to this long after a DISARM/SHUTDOWN request for the bridge is its
// answer, not a watchdog trip (a tick is dated no earlier than it was sampled, but allow for the
// request reaching the logger after the bridge).
constexpr std::int64_t kRequestBefore_us = 200'000;
constexpr std::int64_t kRequestAfter_us = 50'000;

bool armed(const SampleRecord& s) { return (s.flags & sensor_block_t::SAFE_STATE) == 0; }

// True when a DISARM or SHUTDOWN request for the bridge explains a safe state entered at utime.
bool requested_safe(const RunData& run, const std::string& bridge, std::int64_t utime) {
  return std::any_of(run.safe_requests.begin(), run.safe_requests.end(), [&](const SafeRequestRecord& r) {
    return (r.target.empty() || r.target == bridge) && r.recv_utime >= utime - kRequestBefore_us &&
           r.recv_utime <= utime + kRequestAfter_us;
  });
}

void fill_params(const RunData& run, double lo, double hi, ReportMetrics& m) {
  const double start = m.first_sample_t_s.value_or(lo);
  const ParamsRecord* initial = nullptr;         // the last valid set at or before the first tick
  const ParamsRecord* first_in_range = nullptr;  // else the first valid set of the range
  for (const auto& p : run.params) {
    const double t = run.t_s(p.recv_utime);
    if (t > hi) continue;
    if (t >= lo) {
      const bool seen = std::any_of(m.params_history.begin(), m.params_history.end(),
                                    [&](const ParamsPoint& h) { return h.version == p.version && h.valid == p.valid; });
      if (!seen) {
        m.params_history.push_back(
            {t, p.version, p.c1, p.c2, p.c3, p.residual_m, p.valid, p.model, p.heldout_rms_m, p.model_channel});
      }
    }
    if (p.model != "mem") continue;  // params_initial/final are MEM sets
    if (p.valid && t <= start) initial = &p;
    if (p.valid && t >= lo && first_in_range == nullptr) first_in_range = &p;
  }
  if (initial == nullptr) initial = first_in_range;
  if (initial == nullptr) return;
  m.params_initial = MemParams{initial->version, initial->c1, initial->c2, initial->c3};
  MemParams current = *m.params_initial;
  for (const auto& p : run.params) {
    const double t = run.t_s(p.recv_utime);
    if (!p.valid || p.model != "mem" || &p == initial || t <= start || t < lo || t > hi) continue;
    if (p.version != current.version) ++m.params_updates;
    current = MemParams{p.version, p.c1, p.c2, p.c3};
  }
  m.params_final = current;
}

// Buffer depth of the armed sensor blocks, and the tick period.
void fill_blocks(const RunData& run, double lo, double hi, ReportMetrics& m) {
  for (const auto& b : run.sensor_blocks) {
    const double t = run.t_s(b.recv_utime);
    if (t < lo || t > hi) continue;
    ++m.sensor_blocks;
    if (!m.tick_period_s) m.tick_period_s = b.dt_s;
    if (!b.armed) continue;
    ++m.armed_blocks;
    m.buffer_min_depth_ticks = std::min(m.buffer_min_depth_ticks.value_or(b.buffer_depth_ticks), b.buffer_depth_ticks);
  }
  for (const auto& c : run.command_blocks) {
    const double t = run.t_s(c.recv_utime);
    if (t < lo || t > hi || c.sample_seq < 0) continue;
    m.run_ahead_ticks.push_back(static_cast<double>(c.seq - c.sample_seq));
  }
  std::sort(m.run_ahead_ticks.begin(), m.run_ahead_ticks.end());
  m.run_ahead_min_ticks = nearest_rank(m.run_ahead_ticks, 0.0);
  m.run_ahead_p01_ticks = nearest_rank(m.run_ahead_ticks, 0.01);
  m.run_ahead_p50_ticks = nearest_rank(m.run_ahead_ticks, 0.50);
  m.run_ahead_max_ticks = nearest_rank(m.run_ahead_ticks, 1.0);
}

// Events of each channel received within the sampled span, per second of it.
void fill_message_rates(const RunData& run, ReportMetrics& m) {
  for (const auto& [channel, times] : run.event_times) {
    if (!m.first_sample_t_s || !(m.duration_s > 0.0)) {
      m.messages_per_s[channel] = std::nullopt;
      continue;
    }
    const double first = *m.first_sample_t_s, last = *m.last_sample_t_s;
    const auto n = std::count_if(times.begin(), times.end(), [&](std::int64_t utime) {
      const double t = run.t_s(utime);
      return t >= first && t <= last;
    });
    m.messages_per_s[channel] = static_cast<double>(n) / m.duration_s;
  }
}

}  // namespace

void ReportOptions::validate() const {
  if (from_s) require_finite("--from", *from_s);
  if (to_s) require_finite("--to", *to_s);
  require_non_negative("--skip-initial", skip_initial_s);
  if (to_s && *to_s < lower_s()) {
    throw ParameterError("--to", "must not be before --from + --skip-initial (got " + std::to_string(*to_s) + " < " +
                                     std::to_string(lower_s()) + ")");
  }
}

double ReportOptions::lower_s() const noexcept {
  if (!from_s && skip_initial_s == 0.0) return -std::numeric_limits<double>::infinity();
  return from_s.value_or(0.0) + skip_initial_s;
}

double ReportOptions::upper_s() const noexcept { return to_s.value_or(std::numeric_limits<double>::infinity()); }

std::optional<double> nearest_rank(const std::vector<double>& sorted, double q) noexcept {
  if (sorted.empty()) return std::nullopt;
  const double n = static_cast<double>(sorted.size());
  auto rank = static_cast<std::size_t>(std::ceil(q * n));
  rank = std::clamp<std::size_t>(rank, 1, sorted.size());
  return sorted[rank - 1];
}

std::vector<TrackPoint> track_points(const RunData& run, const ReportOptions& options) {
  const double lo = options.lower_s(), hi = options.upper_s();
  std::vector<TrackPoint> points;
  points.reserve(run.samples.size());
  for (const auto& s : run.samples) {
    const double t = run.t_s(s.recv_utime);
    if (t < lo || t > hi) continue;
    const VersionRun* command = run.command_versions.run_at(s.seq);
    points.push_back({t, s.u_V, s.y_m, s.y_ref_m, command != nullptr ? command->mode : VersionRun::kUnknownMode,
                      command != nullptr ? std::optional<std::int32_t>(command->version) : std::nullopt, armed(s)});
  }
  return points;
}

ReportMetrics compute_metrics(const RunData& run, const ReportOptions& options) {
  ReportMetrics m;
  m.axis = run.axis;
  m.log_axes = run.sensor_blocks_by_axes.empty() ? 0 : run.sensor_blocks_by_axes.rbegin()->first;
  m.channels = run.channel_counts;
  m.events = run.events;
  m.undecodable = run.undecodable;
  m.signatures_verified = run.signatures_verified;
  for (const LogFileScan& f : run.files) {
    m.unverified_left_out += f.unverified_left_out;
    m.recorded_keyed = m.recorded_keyed || f.recorded_keyed;
  }

  const std::int64_t t0 = run.time_zero_utime();
  const double lo = options.lower_s(), hi = options.upper_s();

  struct BinSum {
    RmsSum error;
    std::optional<std::int32_t> version;
    std::size_t clamped = 0;
  };
  std::map<std::int64_t, BinSum> bins;
  std::vector<std::pair<double, double>> track;  // (t_s, e_m)
  RmsSum all;
  const SampleRecord* prev = nullptr;
  std::int64_t safe_transitions = 0;
  std::optional<std::int32_t> applied;  // the version of the last tick with a logged command

  for (const auto& s : run.samples) {
    const double t = run.t_s(s.recv_utime);
    if (t < lo || t > hi) continue;
    ++m.samples;
    if (!m.first_sample_t_s) m.first_sample_t_s = t;
    m.last_sample_t_s = t;
    if (prev != nullptr && s.seq > prev->seq + 1) {
      ++m.seq_gaps;
      m.missing_samples += s.seq - prev->seq - 1;
    }
    if (armed(s)) {
      ++m.armed_samples;
      if ((s.flags & sensor_block_t::LATE_COMMAND) != 0) ++m.late_samples;
    } else if (prev != nullptr && armed(*prev) && !requested_safe(run, options.bridge_process, s.recv_utime)) {
      ++safe_transitions;
    }
    prev = &s;
    BinSum& bin = bins[static_cast<std::int64_t>(std::floor(t))];
    if (const auto version = run.command_versions.at(s.seq)) {
      bin.version = *version;
      if (applied && *applied != *version) m.swaps.push_back({t, s.seq, *applied, *version});
      applied = version;
    }
    const bool range_clamped = (s.flags & sensor_block_t::SATURATED) != 0;
    const bool slew_clamped = (s.flags & sensor_block_t::SLEW_LIMITED) != 0;
    m.clamped_range_samples += range_clamped ? 1 : 0;
    m.clamped_slew_samples += slew_clamped ? 1 : 0;
    if (range_clamped || slew_clamped) {
      ++m.clamped_samples;
      ++bin.clamped;
    }
    if (!std::isfinite(s.y_ref_m)) continue;
    const double e = s.y_ref_m - s.y_m;
    bin.error.add(e);
    all.add(e);
    track.emplace_back(t, e);
  }
  if (m.first_sample_t_s) m.duration_s = *m.last_sample_t_s - *m.first_sample_t_s;

  // Tracking figures.
  m.tracking_samples = track.size();
  if (!track.empty()) {
    m.rms_error_m = all.rms();
    double max_abs = 0.0, t_first = track.front().first, t_last = track.front().first;
    for (const auto& [t, e] : track) {
      max_abs = std::max(max_abs, std::abs(e));
      t_first = std::min(t_first, t);
      t_last = std::max(t_last, t);
    }
    m.max_abs_error_m = max_abs;
    RmsSum first, last;
    for (const auto& [t, e] : track) {
      if (t < t_first + 5.0) first.add(e);
      if (t > t_last - 5.0) last.add(e);
    }
    m.rms_error_first_5s_m = first.rms();
    m.rms_error_last_5s_m = last.rms();
  }

  // One line per second, empty seconds included, the version carried forward.
  if (!bins.empty()) {
    std::int32_t version = 0;
    for (std::int64_t second = bins.begin()->first; second <= bins.rbegin()->first; ++second) {
      SecondBin out;
      out.t_s = static_cast<double>(second);
      if (const auto it = bins.find(second); it != bins.end()) {
        if (it->second.version) version = *it->second.version;
        out.tracking_samples = it->second.error.n;
        out.clamped_samples = it->second.clamped;
        out.rms_error_m = it->second.error.rms();
      }
      out.params_version = version;
      m.per_second.push_back(out);
    }
  }

  if (m.armed_samples > 0) {
    m.late_command_fraction = static_cast<double>(m.late_samples) / static_cast<double>(m.armed_samples);
  }
  fill_blocks(run, lo, hi, m);
  fill_message_rates(run, m);

  const std::int64_t upper_utime = std::isfinite(hi) ? t0 + static_cast<std::int64_t>(std::floor(hi * 1e6))
                                                     : std::numeric_limits<std::int64_t>::max();
  const std::int64_t lower_utime = std::isfinite(lo) ? t0 + static_cast<std::int64_t>(std::ceil(lo * 1e6))
                                                     : std::numeric_limits<std::int64_t>::min();
  fill_commands_rejected(run, options, upper_utime, m);
  fill_logger_gaps(run, options, upper_utime, m);
  fill_watchdog_trips(run, options, upper_utime, safe_transitions, m);
  fill_cpu_fraction(run, lower_utime, upper_utime, m);
  fill_params(run, lo, hi, m);
  return m;
}

}  // namespace hystloop::report
