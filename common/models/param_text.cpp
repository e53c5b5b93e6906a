#include "models/param_text.hpp"

#include "core/errors.hpp"

namespace hystloop {

void append_yaml_row(std::string& out, std::string& open_map, std::string_view name, ValueKind kind,
                     const std::string& text, std::string_view unit) {
  const std::size_t dot = name.find('.');
  const std::string_view map = dot == std::string_view::npos ? std::string_view() : name.substr(0, dot);
  const std::string_view key = dot == std::string_view::npos ? name : name.substr(dot + 1);
  if (map != open_map) {
    open_map = std::string(map);
    if (!map.empty()) out.append("  ").append(map).append(":\n");
  }
  out.append(map.empty() ? "  " : "    ").append(key).append(": ");
  if (kind == ValueKind::list) {
    // show() joins with ',' (the --param form); YAML's flow sequence reads better spaced.
    out += '[';
    for (const char c : text) {
      out += c;
      if (c == ',') out += ' ';
    }
    out += ']';
  } else {
    out += text;
  }
  if (!unit.empty() && unit != "-") out.append("  # [").append(unit).append("]");
  out += '\n';
}

std::string summary_item(std::string_view name, ValueKind kind, const std::string& text, std::string_view unit) {
  std::string out = std::string(name) + " ";
  double v = 0.0;
  if (kind == ValueKind::number && parse_finite_double(text, v)) {
    out += number_text(v);
  } else {
    out += text;
  }
  if (!unit.empty() && unit != "-") out.append(" ").append(unit);
  return out;
}

}  // namespace hystloop
