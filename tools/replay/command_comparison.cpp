#include "command_comparison.hpp"

#include <bit>
#include <cmath>
#include <iterator>

#include <spdlog/fmt/fmt.h>

#include "core/errors.hpp"

namespace hystloop::replay {
namespace {

bool same(double expected, double got, double tolerance) noexcept {
  if (std::isnan(expected) || std::isnan(got)) return std::isnan(expected) && std::isnan(got);
  if (tolerance == 0.0) return std::bit_cast<std::uint64_t>(expected) == std::bit_cast<std::uint64_t>(got);
  return std::fabs(expected - got) <= tolerance;
}

// The fields of one tick, in report order; returns how many differ and fills the first.
int compare_tick(const RecordedCommand& e, const RecordedCommand& a, const CompareTolerance& tol, Divergence& first) {
  struct Field {
    const char* name;
    double expected;
    double got;
    double tolerance;
  };
  const Field fields[kComparedFields] = {
      {"u_ff_V", e.u_ff_V, a.u_ff_V, tol.voltage_V},
      {"y_ref_m", e.y_ref_m, a.y_ref_m, tol.position_m},
      {"mode", static_cast<double>(e.mode), static_cast<double>(a.mode), 0.0},
      {"params_version", static_cast<double>(e.params_version), static_cast<double>(a.params_version), 0.0},
  };
  int differing = 0;
  for (const Field& f : fields) {
    if (same(f.expected, f.got, f.tolerance)) continue;
    if (differing++ == 0) first = {e.seq, e.sample_seq, f.name, f.expected, f.got, 0};
  }
  first.fields_differing = differing;
  return differing;
}

// Lowest sample seq the replay answered and the highest (for loss detection without a played set).
struct AnsweredRange {
  std::int64_t lo = 0;
  std::int64_t hi = -1;
  bool contains(std::int64_t s) const noexcept { return s >= lo && s <= hi; }
};

AnsweredRange answered_range(const CommandLog& actual) {
  AnsweredRange r;
  bool any = false;
  for (const auto& [seq, c] : actual.by_seq) {
    if (!any || c.sample_seq < r.lo) r.lo = c.sample_seq;
    if (!any || c.sample_seq > r.hi) r.hi = c.sample_seq;
    any = true;
  }
  return r;
}

}  // namespace

void CompareTolerance::validate() const {
  require_non_negative("tolerance_V", voltage_V);
  require_finite("tolerance_V", voltage_V);
  require_non_negative("tolerance_m", position_m);
  require_finite("tolerance_m", position_m);
}

const char* to_string(CompareVerdict verdict) noexcept {
  switch (verdict) {
    case CompareVerdict::kEqual: return "equal";
    case CompareVerdict::kDiverged: return "diverged";
    case CompareVerdict::kTransportLoss: return "transport loss";
  }
  return "?";
}

CompareVerdict CompareReport::verdict() const noexcept {
  if (compared == 0 || missing_in_actual > 0) return CompareVerdict::kDiverged;
  if (first_divergence && !divergence_after_loss) return CompareVerdict::kDiverged;
  if (lost_in_transport > 0) return CompareVerdict::kTransportLoss;
  return first_divergence ? CompareVerdict::kDiverged : CompareVerdict::kEqual;
}

int CompareReport::exit_code() const noexcept {
  // A divergence, or a transport loss (no verdict on the law), is a runtime failure (0/1/2 contract).
  return verdict() == CompareVerdict::kEqual ? 0 : 1;
}

CompareReport compare_commands(const CommandLog& expected, const CommandLog& actual,
                               const std::set<std::int64_t>* played_samples, const CompareTolerance& tolerance) {
  tolerance.validate();
  CompareReport r;
  const AnsweredRange range = answered_range(actual);
  for (const auto& [seq, e] : expected.by_seq) {
    ++r.expected_ticks;
    const auto it = actual.by_seq.find(seq);
    if (it == actual.by_seq.end()) {
      const bool played = played_samples ? played_samples->count(e.sample_seq) > 0 : range.contains(e.sample_seq);
      if (played) {
        ++r.lost_in_transport;
        if (!r.first_lost_sample || e.sample_seq < *r.first_lost_sample) r.first_lost_sample = e.sample_seq;
      } else {
        ++r.missing_in_actual;
        if (!r.first_missing_seq) r.first_missing_seq = seq;
      }
      continue;
    }
    ++r.compared;
    if (!r.first_seq) r.first_seq = seq;
    r.last_seq = seq;
    Divergence d;
    if (compare_tick(e, it->second, tolerance, d) == 0) {
      ++r.equal;
    } else {
      ++r.differing;
      if (!r.first_divergence) r.first_divergence = d;
    }
  }
  // A tick the replay commanded but the original did not (e.g. before it started answering).
  for (const auto& [seq, a] : actual.by_seq) {
    if (expected.by_seq.count(seq) == 0) ++r.missing_in_expected;
  }
  r.divergence_after_loss =
      r.first_divergence && r.first_lost_sample && r.first_divergence->sample_seq >= *r.first_lost_sample;
  return r;
}

std::string format_report(const CompareReport& r, const CompareTolerance& tolerance) {
  std::string out;
  if (tolerance.voltage_V == 0.0 && tolerance.position_m == 0.0) {
    out += "comparison: exact (doubles bitwise equal; mode and params_version equal)\n";
  } else {
    out += fmt::format(
        "comparison: |expected - got| <= {:.6g} V (u_ff_V), <= {:.6g} m (y_ref_m); mode and params_version equal\n",
        tolerance.voltage_V, tolerance.position_m);
  }
  if (r.first_divergence) {
    const Divergence& d = *r.first_divergence;
    out += fmt::format(
        "FIRST DIVERGENCE at tick {} (answering sample {}): {} expected {:.17g} got {:.17g} (difference "
        "{:.3g}; {} of {} fields differ at this tick)\n",
        d.seq, d.sample_seq, d.field, d.expected, d.got, d.got - d.expected, d.fields_differing, kComparedFields);
  }
  if (r.first_missing_seq) {
    out += fmt::format(
        "FIRST MISSING: tick {} was commanded by the original, not by the replay (its sample was not played)\n",
        *r.first_missing_seq);
  }
  if (r.lost_in_transport > 0) {
    out += fmt::format(
        "replay transport lost {} commanded ticks (first planned at sample {}): the sample was played, "
        "the command never logged; not counted as divergence\n",
        r.lost_in_transport, *r.first_lost_sample);
    if (r.divergence_after_loss)
      out += "the first divergence comes after the first lost sample and may be its consequence: replay again\n";
  }
  out += fmt::format(
      "summary: original commanded {} ticks; compared {} (ticks {}..{}): {} equal, {} differing; "
      "missing in replay {} (+ {} lost in transport); replay-only ticks (not compared) {}\n",
      r.expected_ticks, r.compared, r.first_seq.value_or(-1), r.last_seq.value_or(-1), r.equal, r.differing,
      r.missing_in_actual, r.lost_in_transport, r.missing_in_expected);
  if (r.compared == 0) out += "nothing was compared: the replay answered none of the original's ticks\n";
  out += fmt::format("verdict: {}\n", to_string(r.verdict()));
  return out;
}

}  // namespace hystloop::replay
