// Parameter tables of mem, pi, linear and banning (katalenic's is in model_tables_katalenic.cpp).
// Names are the parameter structs' member names, which are also the keys hystloop-identify writes
// in its YAML (ident/params_yaml.cpp) and the compensator's config keys, so a fitted file reads
// back unchanged everywhere.
#include <cstdio>
#include <string>

#include "core/errors.hpp"
#include "models/model_descriptors.hpp"
#include "models/param_fields.hpp"

namespace hystloop {

// ---- mem ----------------------------------------------------------------------------------------

std::span<const ParamSpec<MemParams>> MemDescriptor::table() {
  static const ParamSpec<MemParams> rows[] = {
      summarised(number<MemParams>(
          "c1", "m/V", "slope right after a reversal, M(0) = c1", [](auto& p) -> auto& { return p.c1; })),
      summarised(number<MemParams>(
          "c2", "m/V^(1+c3)", "growth of the slope with the distance p from the reversal",
          [](auto& p) -> auto& { return p.c2; })),
      summarised(number<MemParams>(
          "c3", "-", "exponent of that growth, M(p) = c1 + c2 p^c3", [](auto& p) -> auto& { return p.c3; })),
  };
  return rows;
}

// ---- linear -------------------------------------------------------------------------------------

std::span<const ParamSpec<LinearParams>> LinearDescriptor::table() {
  static const ParamSpec<LinearParams> rows[] = {
      summarised(number<LinearParams>(
          "gain", "m/V", "slope (default: chord of the default MEM's +-250 V loop)",
          [](auto& p) -> auto& { return p.gain; })),
      summarised(number<LinearParams>(
          "offset", "m", "output at u = 0", [](auto& p) -> auto& { return p.offset; })),
  };
  return rows;
}

// ---- pi -----------------------------------------------------------------------------------------

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

// ---- banning ------------------------------------------------------------------------------------

std::span<const ParamSpec<BanningStageParams>> BanningDescriptor::table() {
  using P = BanningStageParams;
  static const ParamSpec<P> rows[] = {
      summarised(number<P>(
          "hysteresis.a", "m/V", "slope of f: loop centres lie on w = a u",
          [](auto& p) -> auto& { return p.hysteresis.a; })),
      summarised(number<P>(
          "hysteresis.b", "m/V", "slope of small loops, a/2 <= b <= a",
          [](auto& p) -> auto& { return p.hysteresis.b; })),
      summarised(number<P>(
          "hysteresis.alpha", "1/V", "relaxation rate onto f after a reversal",
          [](auto& p) -> auto& { return p.hysteresis.alpha; })),
      summarised(number<P>(
          "hysteresis.s_max", "V", "saturation of f and g", [](auto& p) -> auto& { return p.hysteresis.s_max; })),
      summarised(number<P>(
          "stage.k", "1/s^2", "stiffness, omega_n^2", [](auto& p) -> auto& { return p.stage.k; })),
      summarised(number<P>(
          "stage.c", "1/s", "damping, 2 zeta omega_n", [](auto& p) -> auto& { return p.stage.c; })),
      custom<P>(
          "order", "-", "which comes first: hysteresis (the bridge's) or the stage (the paper's)", ValueKind::choice,
          [](P& p, const ParsedValue& v) {
            p.order = v.choice == "stage_then_hysteresis" ? BanningOrder::kStageThenHysteresis
                                                          : BanningOrder::kHysteresisThenStage;
          },
          [](const P& p) {
            return std::string(p.order == BanningOrder::kStageThenHysteresis ? "stage_then_hysteresis"
                                                                             : "hysteresis_then_stage");
          },
          "hysteresis_then_stage|stage_then_hysteresis"),
  };
  return rows;
}

}  // namespace hystloop
