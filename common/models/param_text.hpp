#pragma once
// A parameter set as text, through its model's table (param_table.hpp): the YAML section
// hystloop-identify writes and every reader reads back through the same table, and the one-line
// summary the services log. Names with a dot ("input_shaping.gain") are one level of nesting:
//
//   katalenic:
//     k1: 40  # [x]
//     input_shaping:
//       kind: linear
//       gain: 1  # [x/V]
//
// Numbers are the shortest text that reads back to the same double, so a set survives
// YAML -> params -> YAML unchanged. Start-up only, never on the per-sample path.

#include <span>
#include <string>
#include <string_view>

#include "models/param_table.hpp"

namespace hystloop {

// One row of a section: `name` may hold one dot (a nested map); rows of one map are adjacent.
// `open_map` is the map the previous row was in (updated).
void append_yaml_row(std::string& out, std::string& open_map, std::string_view name, ValueKind kind,
                     const std::string& text, std::string_view unit);

// "c1 5.3e-09 m/V": a number at 6 significant digits, the unit left out when dimensionless.
std::string summary_item(std::string_view name, ValueKind kind, const std::string& text, std::string_view unit);

// "<model>:\n  <row>: <value>  # [unit]\n...": every row that applies to `s` and that `keep`
// (when given) keeps.
template <class S>
std::string yaml_section(std::string_view model, std::span<const ParamSpec<S>> table, const S& s,
                         bool (*keep)(std::string_view name) = nullptr) {
  std::string out = std::string(model) + ":\n";
  std::string open_map;
  for (const auto& p : table) {
    if ((p.applies != nullptr && !p.applies(s)) || (keep != nullptr && !keep(p.name))) continue;
    append_yaml_row(out, open_map, p.name, p.kind, p.show(s), p.unit);
  }
  return out;
}

// "c1 5.3e-09 m/V, c2 2.1e-12 m/V^(1+c3), c3 1.15": the rows marked in_summary.
template <class S>
std::string summary_line(std::span<const ParamSpec<S>> table, const S& s) {
  std::string out;
  for (const auto& p : table) {
    if (!p.in_summary) continue;
    if (!out.empty()) out += ", ";
    out += summary_item(p.name, p.kind, p.show(s), p.unit);
  }
  return out;
}

// A model whose table stores straight into its parameter struct (all but PI); D is the model's
// descriptor, which declares table().
template <class D, class P>
struct StoresParams {
  using Settings = P;
  using Params = P;
  static constexpr std::string_view notes = "";  // extra help lines
  static Params build(const Settings& s) { return s; }
  static Settings settings_of(const Params& p) { return p; }
  static std::string summary_of(const Params& p) { return summary_line(D::table(), p); }  // the in_summary rows
};

}  // namespace hystloop
