#include "models/param_table.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "core/edit_distance.hpp"

namespace hystloop {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

AssignmentError::AssignmentError(const Assignment& a, const std::string& reason)
    : ParameterError(a.name, reason), message_(a.origin + ": " + reason) {}

std::string_view to_string(ValueKind kind) noexcept {
  switch (kind) {
    case ValueKind::number: return "number";
    case ValueKind::count: return "integer";
    case ValueKind::list: return "list";
    case ValueKind::choice: return "choice";
  }
  return "?";
}

bool parse_finite_double(std::string_view text, double& out, std::string* why) {
  text = trim(text);
  // from_chars is locale independent (a user's LC_NUMERIC=de_DE must not turn "1.5" into 1) but
  // takes no leading '+'.
  std::string_view body = text;
  if (body.size() > 1 && body.front() == '+' && body[1] != '-' && body[1] != '+') body.remove_prefix(1);
  double v = 0.0;
  const auto [end, ec] = std::from_chars(body.data(), body.data() + body.size(), v);
  if (body.empty() || ec == std::errc::invalid_argument || end != body.data() + body.size()) {
    if (why != nullptr) *why = "expected a number";
    return false;
  }
  if (ec == std::errc::result_out_of_range || !std::isfinite(v)) {
    if (why != nullptr) *why = "expected a finite number";
    return false;
  }
  out = v;
  return true;
}

double parse_number(const Assignment& a) {
  double v = 0.0;
  std::string why;
  if (!parse_finite_double(a.value, v, &why)) throw AssignmentError(a, why + ", got '" + a.value + "'");
  return v;
}

std::size_t parse_count(const Assignment& a) {
  const std::string_view text = trim(a.value);
  std::size_t v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size()) {
    throw AssignmentError(a, "expected a whole number >= 0, got '" + a.value + "'");
  }
  return v;
}

std::vector<double> parse_list(const Assignment& a) {
  std::string_view text = trim(a.value);
  if (text.size() >= 2 && text.front() == '[' && text.back() == ']') text = trim(text.substr(1, text.size() - 2));
  if (text.empty()) throw AssignmentError(a, "expected a comma-separated list of numbers, got '" + a.value + "'");
  std::vector<double> out;
  std::size_t index = 0;
  while (true) {
    const std::size_t comma = text.find(',');
    const std::string_view item = text.substr(0, comma);
    double v = 0.0;
    std::string why;
    if (!parse_finite_double(item, v, &why)) {
      throw AssignmentError(a,
                            "entry " + std::to_string(index) + ": " + why + ", got '" + std::string(trim(item)) + "'");
    }
    out.push_back(v);
    ++index;
    if (comma == std::string_view::npos) break;
    text.remove_prefix(comma + 1);
  }
  return out;
}

std::string parse_choice(const Assignment& a, std::string_view choices) {
  const std::string_view text = trim(a.value);
  std::string_view rest = choices;
  while (!rest.empty()) {
    const std::size_t bar = rest.find('|');
    if (rest.substr(0, bar) == text) return std::string(text);
    if (bar == std::string_view::npos) break;
    rest.remove_prefix(bar + 1);
  }
  throw AssignmentError(a, "expected one of " + std::string(choices) + ", got '" + a.value + "'");
}

ParsedValue parse_value(const Assignment& a, ValueKind kind, std::string_view choices) {
  ParsedValue v;
  switch (kind) {
    case ValueKind::number: v.number = parse_number(a); break;
    case ValueKind::count: v.count = parse_count(a); break;
    case ValueKind::list: v.list = parse_list(a); break;
    case ValueKind::choice: v.choice = parse_choice(a, choices); break;
  }
  return v;
}

Assignment split_assignment(const std::string& text, const std::string& origin_prefix) {
  Assignment a;
  a.origin = origin_prefix + " " + text;
  const std::size_t eq = text.find('=');
  a.name = std::string(trim(std::string_view(text).substr(0, eq)));
  if (eq == std::string::npos || a.name.empty()) {
    throw AssignmentError(a, "expected NAME=VALUE (e.g. c1=5e-9), got '" + text + "'");
  }
  a.value = text.substr(eq + 1);
  return a;
}

std::string closest_name(std::string_view name, std::span<const std::string> candidates) {
  std::string best;
  std::size_t best_d = std::string::npos;
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(name, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  // A typo, not a different word: at most a third of the name wrong (and at least 1 edit allowed).
  const std::size_t limit = std::max<std::size_t>(1, std::max(name.size(), best.size()) / 3);
  return best_d <= limit ? best : std::string();
}

void throw_unknown(const Assignment& a, std::string_view model, const std::vector<ParamInfo>& valid) {
  std::vector<std::string> names;
  for (const auto& p : valid) {
    names.push_back(p.name);
    if (!p.alias.empty()) names.push_back(p.alias);
  }
  std::string reason = "unknown parameter '" + a.name + "' of model " + std::string(model);
  const std::string guess = closest_name(a.name, names);
  if (!guess.empty()) reason += "; did you mean '" + guess + "'?";
  reason += " (valid:";
  for (std::size_t i = 0; i < valid.size(); ++i) {
    reason += i ? ", " : " ";
    reason += valid[i].name;
  }
  reason += ")";
  throw AssignmentError(a, reason);
}

std::string format_number(double v) {
  // The shortest text that reads back to the same double (C locale, fixed or exponent, whichever
  // is shorter): exact like %.17g, without its 0.0030000000000000001.
  char buf[40];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return ec == std::errc() ? std::string(buf, end) : std::string("?");
}

std::string format_list(std::span<const double> v) {
  std::string out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (i > 0) out += ',';
    out += format_number(v[i]);
  }
  return out;
}

}  // namespace hystloop
