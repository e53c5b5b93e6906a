#pragma once
// Builders for parameter-table rows (param_table.hpp). `Ref` is a captureless generic lambda that
// returns a reference to the field inside the settings struct, e.g.
//
//   number<MemParams>("c1", "m/V", "slope right after a reversal", [](auto& p) -> auto& { return p.c1; })
//
// Captureless closures are default constructible (C++20), so the row stores plain function
// pointers and the table stays a flat array.

#include <string>
#include <string_view>

#include "models/param_table.hpp"

namespace hystloop {

// A row with its own set/show (lists, choices, counts, values that need a conversion).
template <class S>
ParamSpec<S> custom(std::string_view name, std::string_view unit, std::string_view description, ValueKind kind,
                    void (*set)(S&, const ParsedValue&), std::string (*show)(const S&), std::string_view choices = {},
                    std::string_view alias = {}) {
  ParamSpec<S> p;
  p.name = name;
  p.alias = alias;
  p.unit = unit;
  p.description = description;
  p.kind = kind;
  p.choices = choices;
  p.set = set;
  p.show = show;
  return p;
}

// A number stored in the field `Ref` returns.
template <class S, class Ref>
ParamSpec<S> number(std::string_view name, std::string_view unit, std::string_view description, Ref,
                    std::string_view alias = {}) {
  return custom<S>(
      name, unit, description, ValueKind::number, [](S& s, const ParsedValue& v) { Ref{}(s) = v.number; },
      [](const S& s) { return format_number(Ref{}(s)); }, {}, alias);
}

// The row, named in one-line summaries (param_text.hpp: summary_line).
template <class S>
ParamSpec<S> summarised(ParamSpec<S> p) {
  p.in_summary = true;
  return p;
}

// The row, written only where `applies` says the value means something for the set.
template <class S>
ParamSpec<S> only_if(ParamSpec<S> p, bool (*applies)(const S&)) {
  p.applies = applies;
  return p;
}

}  // namespace hystloop
