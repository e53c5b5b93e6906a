// PI's parameter table (its operators, or a size and a range with weights matched to a MEM), how
// the settings become PiParams, and its gain band.
#include "models/model_set.hpp"

#include <algorithm>
#include <cstdio>
#include <string>

#include "core/errors.hpp"
#include "models/param_fields.hpp"

namespace hystloop {

static_assert(kPiMaxOperators == 32, "the help text of count says 1..32");

namespace {

// What a PI set given by its plays leaves out of its YAML: the range it was not built from.
bool spans_range(const PiSettings& s) { return s.thresholds.empty(); }
bool has_thresholds(const PiSettings& s) { return !s.thresholds.empty(); }
bool has_weights(const PiSettings& s) { return !s.weights.empty(); }

}  // namespace

// count and range_V are the compensator's config keys (units in the name); n and u_max, the
// names hystloop-model took first, stay accepted.
std::span<const ParamSpec<PiSettings>> PiDescriptor::table() {
  static const ParamSpec<PiSettings> rows[] = {
      custom<PiSettings>(
          "count", "-", "number of play operators (1..32)", ValueKind::count,
          [](PiSettings& s, const ParsedValue& v) {
            s.count = v.count;
            s.count_given = true;
          },
          [](const PiSettings& s) { return std::to_string(s.count); }, {}, "n"),
      only_if(number<PiSettings>(
                  "range_V", "V", "input amplitude the even thresholds span (r_i = i*range_V/count)",
                  [](auto& s) -> auto& { return s.range_V; }, "u_max"),
              &spans_range),
      only_if(custom<PiSettings>(
                  "thresholds", "V", "r_0 = 0 < r_1 < ... (needs weights)", ValueKind::list,
                  [](PiSettings& s, const ParsedValue& v) { s.thresholds = v.list; },
                  [](const PiSettings& s) {
                    return s.thresholds.empty() ? std::string("even") : format_list(s.thresholds);
                  }),
              &has_thresholds),
      only_if(custom<PiSettings>(
                  "weights", "m/V", "w_0 > 0, cumulative sums > 0", ValueKind::list,
                  [](PiSettings& s, const ParsedValue& v) { s.weights = v.list; },
                  [](const PiSettings& s) {
                    return s.weights.empty() ? std::string("matched to mem") : format_list(s.weights);
                  }),
              &has_weights),
  };
  return rows;
}

PiSettings PiDescriptor::settings_of(const PiParams& p) {
  PiSettings s;
  s.count = p.count;
  s.count_given = true;
  s.thresholds.assign(p.thresholds.begin(), p.thresholds.begin() + static_cast<std::ptrdiff_t>(p.count));
  s.weights.assign(p.weights.begin(), p.weights.begin() + static_cast<std::ptrdiff_t>(p.count));
  return s;
}

std::string PiDescriptor::summary_of(const PiParams& p) {
  char line[64];
  std::snprintf(line, sizeof line, "%zu plays up to %.4g V", p.count, p.count > 0 ? p.thresholds[p.count - 1] : 0.0);
  return line;
}

PiParams PiDescriptor::build(const PiSettings& s) {
  const std::string max_text = std::to_string(kPiMaxOperators);
  if (s.weights.empty()) {
    if (!s.thresholds.empty()) {
      throw ParameterError("thresholds",
                           "given without weights: give weights=w0,w1,... as well (weights are matched "
                           "to the MEM only for even thresholds)");
    }
    if (s.count < 1 || s.count > kPiMaxOperators)
      throw ParameterError("count", "must be in [1, " + max_text + "] (got " + std::to_string(s.count) + ")");
    require_positive("range_V", s.range_V);
    return pi_params_from_mem(s.matched_to, s.count, s.range_V);
  }
  const std::size_t count = s.weights.size();
  if (count > kPiMaxOperators) {
    throw ParameterError("weights", "at most " + max_text + " operators (got " + std::to_string(count) + ")");
  }
  // The weights set the number of plays: thresholds that disagree are refused naming the weights.
  if (!s.thresholds.empty() && s.thresholds.size() != count) {
    throw ParameterError("weights", "has " + std::to_string(count) + " entries but thresholds has " +
                                        std::to_string(s.thresholds.size()));
  }
  if (s.count_given && s.count != count) {
    throw ParameterError("count",
                         "is " + std::to_string(s.count) + " but weights has " + std::to_string(count) + " entries");
  }
  PiParams p;
  if (s.thresholds.empty()) {
    require_positive("range_V", s.range_V);
    p = PiParams::with_even_thresholds(count, s.range_V);
  } else {
    p.count = count;
    for (std::size_t i = 0; i < count; ++i) p.thresholds[i] = s.thresholds[i];
  }
  for (std::size_t i = 0; i < count; ++i) p.weights[i] = s.weights[i];
  return p;
}

namespace {

// The plays a branch or the initial loading curve can engage within a range of R volts.
std::size_t engaged_plays(const PiParams& pi, double range_V) noexcept {
  std::size_t n = 0;
  while (n < pi.count && n < kPiMaxOperators && pi.thresholds[n] < range_V) ++n;
  return std::max<std::size_t>(n, 1);  // r_0 = 0: the identity always is
}

}  // namespace

// The cumulative weights w_0 + ... + w_i of the plays a branch or the initial loading curve can
// engage within the range (r_i < R; the last one is the sum of the weights).
GainRange PiDescriptor::gain_range(const PiParams& p, const GainPlausibility& rig) noexcept {
  const std::size_t n = engaged_plays(p, rig.u_max_V - rig.u_min_V);
  GainRange r{p.weights[0], p.weights[0]};
  double cumulative = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    cumulative += p.weights[i];
    r.min_m_per_V = std::min(r.min_m_per_V, cumulative);
    r.max_m_per_V = std::max(r.max_m_per_V, cumulative);
  }
  return r;
}

// Names the first play whose cumulative weight leaves the band.
void PiDescriptor::refuse_gain(const PiParams& p, const GainRange& g, const GainPlausibility& rig) {
  const double lo = rig.min_gain_m_per_V(), hi = rig.max_gain_m_per_V();
  const std::size_t n = engaged_plays(p, rig.u_max_V - rig.u_min_V);
  double cumulative = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    cumulative += p.weights[i];
    if (!(cumulative >= lo) || !(cumulative <= hi)) {
      refuse_implausible_gain("weights[" + std::to_string(i) + "]",
                              "the slope w_0 + ... + w_" + std::to_string(i) + " of a branch", cumulative,
                              !(cumulative >= lo), rig);
    }
  }
  const bool low = !(g.min_m_per_V >= lo);
  refuse_implausible_gain("weights", "the slope of a branch", low ? g.min_m_per_V : g.max_m_per_V, low, rig);
}

}  // namespace hystloop
