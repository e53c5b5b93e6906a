#include "report_metrics.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>
#include <unordered_map>

#include "core/errors.hpp"

namespace hystloop::report {

namespace {

constexpr std::int32_t kSafeStateFlag = 2;    // sensor_sample_t::SAFE_STATE
constexpr std::int32_t kLateCommandFlag = 16; // sensor_sample_t::LATE_COMMAND

// Index of the first logged command for each tick.
std::unordered_map<std::int64_t, std::size_t> first_command_by_seq(const RunData& run) {
  std::unordered_map<std::int64_t, std::size_t> index;
  index.reserve(run.commands.size());
  for (std::size_t i = 0; i < run.commands.size(); ++i) index.emplace(run.commands[i].seq, i);
  return index;
}

double rms(double sum_sq, std::size_t n) { return std::sqrt(sum_sq / static_cast<double>(n)); }

std::string_view leaf(std::string_view name) {
  const auto dot = name.rfind('.');
  return dot == std::string_view::npos ? name : name.substr(dot + 1);
}

std::string_view endpoint(std::string_view name) {
  const auto dot = name.rfind('.');
  return dot == std::string_view::npos ? std::string_view{} : name.substr(0, dot);
}

// The last status of `process` received at or before t_s <= upper.
const StatusRecord* last_status(const RunData& run, const std::string& process, std::int64_t upper_utime) {
  const StatusRecord* last = nullptr;
  for (const auto& status : run.statuses) {
    if (status.process == process && status.recv_utime <= upper_utime) last = &status;
  }
  return last;
}

// A bridge counter counts as a rejected command when its leaf is "rejected*" or "stale"
// (DESIGN.md: stale commands are rejected) and it is not another endpoint's counter.
bool is_command_reject_counter(std::string_view name) {
  const std::string_view l = leaf(name);
  const std::string_view e = endpoint(name);
  const bool reject = l.starts_with("rejected") || l == "stale";
  const bool commands = e.empty() || e.find("command") != std::string_view::npos || e.find("cmd") != std::string_view::npos;
  return reject && commands;
}

void fill_commands_rejected(const RunData& run, const ReportOptions& options, std::int64_t upper_utime,
                            ReportMetrics& m) {
  const StatusRecord* bridge = last_status(run, options.bridge_process, upper_utime);
  if (bridge == nullptr) {
    m.commands_rejected_source = "no status of process '" + options.bridge_process + "' in the log";
    return;
  }
  std::int64_t sum = 0;
  for (const auto& [name, value] : bridge->counters) {
    if (!is_command_reject_counter(name)) continue;
    sum += value;
    m.commands_rejected_counters.emplace_back(name, value);
  }
  if (!m.commands_rejected_counters.empty()) {
    m.commands_rejected = sum;
    m.commands_rejected_source = "last " + options.bridge_process + " status: sum of its command reject counters";
  } else {
    m.commands_rejected = bridge->rejected;
    m.commands_rejected_source = "last " + options.bridge_process + " status: 'rejected' (no command reject counters)";
  }
}

void fill_logger_gaps(const RunData& run, const ReportOptions& options, std::int64_t upper_utime, ReportMetrics& m) {
  if (const StatusRecord* logger = last_status(run, options.logger_process, upper_utime)) {
    // Most specific name first: "gaps", then "*gaps", then anything with "gap".
    const std::array<bool (*)(std::string_view), 3> tiers{
        [](std::string_view l) { return l == "gaps"; },
        [](std::string_view l) { return l.ends_with("gaps"); },
        [](std::string_view l) { return l.find("gap") != std::string_view::npos; }};
    for (const auto& matches : tiers) {
      std::int64_t sum = 0;
      std::string names;
      for (const auto& [name, value] : logger->counters) {
        if (!matches(leaf(name))) continue;
        sum += value;
        names += (names.empty() ? "" : "+") + name;
      }
      if (!names.empty()) {
        m.logger_gaps = sum;
        m.logger_gaps_source = "last " + options.logger_process + " status: " + names;
        return;
      }
    }
  }
  m.logger_gaps = m.seq_gaps;
  m.logger_gaps_source = "sensor seq (no gap counter from '" + options.logger_process + "')";
}

void fill_params(const RunData& run, double lo, double hi, std::int64_t t0, ReportMetrics& m) {
  auto t_of = [t0](std::int64_t utime) { return static_cast<double>(utime - t0) * 1e-6; };
  const double start = m.first_sample_t_s.value_or(lo);
  const ParamsRecord* initial = nullptr;
  for (const auto& p : run.params) {
    const double t = t_of(p.recv_utime);
    if (t > hi) continue;
    if (t >= lo) {
      const bool seen = std::any_of(m.params_history.begin(), m.params_history.end(),
                                    [&](const ParamsPoint& h) { return h.version == p.version && h.valid == p.valid; });
      if (!seen) m.params_history.push_back({t, p.version, p.c1, p.c2, p.c3, p.residual_m, p.valid});
    }
    if (p.valid && t <= start) initial = &p;
  }
  if (initial == nullptr) {
    for (const auto& p : run.params) {
      const double t = t_of(p.recv_utime);
      if (p.valid && t >= lo && t <= hi) {
        initial = &p;
        break;
      }
    }
  }
  if (initial == nullptr) return;
  m.params_initial = MemParams{initial->version, initial->c1, initial->c2, initial->c3};
  MemParams current = *m.params_initial;
  for (const auto& p : run.params) {
    const double t = t_of(p.recv_utime);
    if (!p.valid || &p == initial || t <= start || t < lo || t > hi) continue;
    if (p.version != current.version) ++m.params_updates;
    current = MemParams{p.version, p.c1, p.c2, p.c3};
  }
  m.params_final = current;
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

std::vector<TrackPoint> matched_ticks(const RunData& run, const ReportOptions& options) {
  const auto commands = first_command_by_seq(run);
  const std::int64_t t0 = run.time_zero_utime();
  const double lo = options.lower_s(), hi = options.upper_s();
  std::vector<TrackPoint> points;
  points.reserve(run.samples.size());
  for (const auto& s : run.samples) {
    const double t = static_cast<double>(s.recv_utime - t0) * 1e-6;
    if (t < lo || t > hi) continue;
    const auto it = commands.find(s.seq);
    const double y_ref = it == commands.end() ? std::nan("") : run.commands[it->second].y_ref_m;
    points.push_back({t, s.u_V, s.y_m, y_ref});
  }
  return points;
}

ReportMetrics compute_metrics(const RunData& run, const ReportOptions& options) {
  ReportMetrics m;
  m.channels = run.channel_counts;
  m.events = run.events;
  m.undecodable = run.undecodable;

  const std::int64_t t0 = run.time_zero_utime();
  auto t_of = [t0](std::int64_t utime) { return static_cast<double>(utime - t0) * 1e-6; };
  const double lo = options.lower_s(), hi = options.upper_s();
  const auto commands = first_command_by_seq(run);

  struct BinSum {
    double sum_sq = 0.0;
    std::size_t n = 0;
    std::optional<std::int32_t> version;
  };
  std::map<std::int64_t, BinSum> bins;
  std::unordered_map<std::int64_t, std::int64_t> sample_recv;  // seq -> receive time of the sample
  sample_recv.reserve(run.samples.size());
  std::vector<std::pair<double, double>> track;  // (t_s, e_m)
  double sum_sq = 0.0;
  std::optional<std::int64_t> prev_seq;

  for (const auto& s : run.samples) {
    const double t = t_of(s.recv_utime);
    if (t < lo || t > hi) continue;
    ++m.samples;
    if (!m.first_sample_t_s) m.first_sample_t_s = t;
    m.last_sample_t_s = t;
    sample_recv.emplace(s.seq, s.recv_utime);
    if (prev_seq && s.seq > *prev_seq + 1) {
      ++m.seq_gaps;
      m.missing_samples += s.seq - *prev_seq - 1;
    }
    prev_seq = s.seq;
    if ((s.flags & kSafeStateFlag) == 0) {
      ++m.armed_samples;
      if ((s.flags & kLateCommandFlag) != 0) ++m.late_samples;
    }
    BinSum& bin = bins[static_cast<std::int64_t>(std::floor(t))];
    const auto it = commands.find(s.seq);
    if (it == commands.end()) continue;
    const CommandRecord& c = run.commands[it->second];
    bin.version = c.params_version;
    if (!std::isfinite(c.y_ref_m)) continue;
    const double e = s.y_m - c.y_ref_m;
    bin.sum_sq += e * e;
    ++bin.n;
    sum_sq += e * e;
    track.emplace_back(t, e);
  }
  if (m.first_sample_t_s) m.duration_s = *m.last_sample_t_s - *m.first_sample_t_s;

  // Tracking figures.
  m.tracking_samples = track.size();
  if (!track.empty()) {
    m.rms_error_m = rms(sum_sq, track.size());
    double max_abs = 0.0, t_first = track.front().first, t_last = track.front().first;
    for (const auto& [t, e] : track) {
      max_abs = std::max(max_abs, std::abs(e));
      t_first = std::min(t_first, t);
      t_last = std::max(t_last, t);
    }
    m.max_abs_error_m = max_abs;
    double first_sq = 0.0, last_sq = 0.0;
    std::size_t first_n = 0, last_n = 0;
    for (const auto& [t, e] : track) {
      if (t < t_first + 5.0) first_sq += e * e, ++first_n;
      if (t > t_last - 5.0) last_sq += e * e, ++last_n;
    }
    m.rms_error_first_5s_m = rms(first_sq, first_n);
    m.rms_error_last_5s_m = rms(last_sq, last_n);
  }

  // One line per second, empty seconds included, the version carried forward.
  if (!bins.empty()) {
    std::int32_t version = 0;
    for (std::int64_t second = bins.begin()->first; second <= bins.rbegin()->first; ++second) {
      SecondBin out;
      out.t_s = static_cast<double>(second);
      if (const auto it = bins.find(second); it != bins.end()) {
        if (it->second.version) version = *it->second.version;
        out.tracking_samples = it->second.n;
        if (it->second.n > 0) out.rms_error_m = rms(it->second.sum_sq, it->second.n);
      }
      out.params_version = version;
      m.per_second.push_back(out);
    }
  }

  if (m.armed_samples > 0) {
    m.late_command_fraction = static_cast<double>(m.late_samples) / static_cast<double>(m.armed_samples);
  }

  for (const auto& c : run.commands) {
    if (c.sample_seq < 0) continue;
    const auto it = sample_recv.find(c.sample_seq);
    if (it == sample_recv.end()) continue;
    m.latencies_us.push_back(static_cast<double>(c.recv_utime - it->second));
  }
  std::sort(m.latencies_us.begin(), m.latencies_us.end());
  m.latency_p50_us = nearest_rank(m.latencies_us, 0.50);
  m.latency_p99_us = nearest_rank(m.latencies_us, 0.99);
  m.latency_max_us = nearest_rank(m.latencies_us, 1.0);

  const std::int64_t upper_utime =
      std::isfinite(hi) ? t0 + static_cast<std::int64_t>(std::floor(hi * 1e6)) : std::numeric_limits<std::int64_t>::max();
  fill_commands_rejected(run, options, upper_utime, m);
  fill_logger_gaps(run, options, upper_utime, m);
  fill_params(run, lo, hi, t0, m);
  return m;
}

}  // namespace hystloop::report
