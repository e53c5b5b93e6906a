#pragma once
// One table per model describes its parameters: name (and an alias, an older spelling), unit,
// meaning, kind of value and how to store it. The same table drives hystloop-model's --help,
// `--param NAME=VALUE` and --params-file, the YAML hystloop-identify writes (param_text.hpp), the
// compensator's model sections and its start-up summary, and the "did you mean" for an unknown
// name, so none of them can disagree on a name. Bounds are the model's validate(): a table only
// stores values, the parameter struct says which sets are valid.
//
// Values are parsed strictly: the whole text must be the value (no trailing junk), numbers in C
// notation and finite, lists comma separated (optionally in [brackets], as YAML writes them).

#include <cstddef>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/errors.hpp"

namespace hystloop {

enum class ValueKind { number, count, list, choice };

struct ParsedValue {
  double number = 0.0;
  std::size_t count = 0;
  std::vector<double> list;
  std::string choice;
};

// One `name=value` from --param or from the params file. `origin` says where it came from, for
// messages: "--param c4=1e-9" or "params.yaml: mem.c4".
struct Assignment {
  std::string name;
  std::string value;
  std::string origin;
};

// An assignment refused before the model validates the whole set (unknown name, malformed value).
// field() is the parameter name; what() is "<origin>: <reason>".
class AssignmentError : public ParameterError {
 public:
  AssignmentError(const Assignment& a, const std::string& reason);
  const char* what() const noexcept override { return message_.c_str(); }

 private:
  std::string message_;
};

// Row of a model's table. S is the settings struct the values are stored into (the model's
// parameter struct itself, or a builder for it such as PI's n/u_max).
template <class S>
struct ParamSpec {
  std::string_view name;
  std::string_view alias;  // accepted as well ("" if none): another spelling users' files or commands hold
  std::string_view unit;   // "m/V", "-" for dimensionless
  std::string_view description;
  ValueKind kind = ValueKind::number;
  std::string_view choices;  // ValueKind::choice: "a|b|c"
  void (*set)(S&, const ParsedValue&) = nullptr;
  std::string (*show)(const S&) = nullptr;  // the current value as text (help shows S{}'s)
  // Whether the value means anything for this set (a tanh's gain does not): nullptr = always.
  // A value that means nothing is left out of the YAML written, so a file says only what counts.
  bool (*applies)(const S&) = nullptr;
  bool in_summary = false;  // one of the few values a one-line summary of the set names
};

// The table row, type-erased for help and listing.
struct ParamInfo {
  std::string name, alias, unit, description, kind, default_text;
};

std::string_view to_string(ValueKind kind) noexcept;

// Strict parsers; throw AssignmentError naming the parameter and quoting the text.
double parse_number(const Assignment& a);
std::size_t parse_count(const Assignment& a);
std::vector<double> parse_list(const Assignment& a);
std::string parse_choice(const Assignment& a, std::string_view choices);
ParsedValue parse_value(const Assignment& a, ValueKind kind, std::string_view choices);

// `s` without the spaces and tabs around it.
std::string_view trim(std::string_view s);

// Strict C-locale number: the whole of `text` (surrounding spaces aside) must be one finite
// double. Returns false otherwise; `why` says "expected a number" or "expected a finite number".
bool parse_finite_double(std::string_view text, double& out, std::string* why = nullptr);

// "NAME=VALUE" -> Assignment; throws AssignmentError without '=' or with an empty name.
Assignment split_assignment(const std::string& text, const std::string& origin_prefix);

// The closest of `candidates` to `name` if it is close enough to be a likely typo, else "".
std::string closest_name(std::string_view name, std::span<const std::string> candidates);

std::string format_number(double v);                 // shortest round-trip text
std::string format_list(std::span<const double> v);  // "a,b,c"

template <class S>
std::vector<ParamInfo> describe(std::span<const ParamSpec<S>> table) {
  std::vector<ParamInfo> out;
  const S defaults{};
  for (const auto& p : table) {
    std::string kind(to_string(p.kind));
    if (p.kind == ValueKind::choice) kind = std::string(p.choices);
    out.push_back({std::string(p.name), std::string(p.alias), std::string(p.unit), std::string(p.description), kind,
                   p.show(defaults)});
  }
  return out;
}

template <class S>
const ParamSpec<S>* find_spec(std::span<const ParamSpec<S>> table, std::string_view name) {
  for (const auto& p : table) {
    if (p.name == name || (!p.alias.empty() && p.alias == name)) return &p;
  }
  return nullptr;
}

// D's (models/model_descriptors.hpp) parameters: the assignments over `settings` (the defaults),
// built and validated. Throws AssignmentError or ParameterError naming the field.
template <class D>
typename D::Params params_from(const std::vector<Assignment>& assignments, typename D::Settings settings = {}) {
  apply(D::table(), D::name, assignments, settings);
  typename D::Params params = D::build(settings);
  params.validate();
  return params;
}

// f(name, value) for every number `s` holds by the table: a number row's value, a list row's
// entries as "name[i]". Read back from show(), which is exact (format_number round-trips).
template <class S, class F>
void for_each_number(std::span<const ParamSpec<S>> table, const S& s, F&& f) {
  for (const auto& p : table) {
    const Assignment shown{std::string(p.name), p.show(s), std::string(p.name)};
    if (p.kind == ValueKind::number) f(shown.name, parse_number(shown));
    if (p.kind != ValueKind::list) continue;
    const std::vector<double> values = parse_list(shown);
    for (std::size_t i = 0; i < values.size(); ++i) f(shown.name + "[" + std::to_string(i) + "]", values[i]);
  }
}

// Refusal of an unknown name, listing the valid ones and the likely one.
[[noreturn]] void throw_unknown(const Assignment& a, std::string_view model, const std::vector<ParamInfo>& valid);

// Applies the assignments in order (a later one overrides an earlier one) onto `settings`.
template <class S>
void apply(std::span<const ParamSpec<S>> table, std::string_view model, const std::vector<Assignment>& assignments,
           S& settings) {
  for (const auto& a : assignments) {
    const ParamSpec<S>* spec = find_spec(table, a.name);
    if (spec == nullptr) throw_unknown(a, model, describe(table));
    const ParsedValue value = parse_value(a, spec->kind, spec->choices);
    try {
      spec->set(settings, value);  // may refuse what the kind alone does not (a list too long)
    } catch (const std::invalid_argument& e) {
      throw AssignmentError(a, e.what());
    }
  }
}

}  // namespace hystloop
