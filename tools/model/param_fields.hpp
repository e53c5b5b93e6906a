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

#include "param_table.hpp"

namespace hystloop::model_tool {

template <class S, class Ref>
ParamSpec<S> number(std::string_view name, std::string_view unit, std::string_view description, Ref,
                    std::string_view alias = {}) {
  ParamSpec<S> p;
  p.name = name;
  p.alias = alias;
  p.unit = unit;
  p.description = description;
  p.kind = ValueKind::number;
  p.set = [](S& s, const ParsedValue& v) { Ref{}(s) = v.number; };
  p.show = [](const S& s) { return format_number(Ref{}(s)); };
  return p;
}

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

}  // namespace hystloop::model_tool
