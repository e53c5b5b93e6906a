#include "core/errors.hpp"

#include <cmath>
#include <cstdio>

namespace hystloop {
// %g keeps SI values such as 8.58e-09 m/V readable (std::to_string would print 0.000000).
std::string refusal_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

void require_finite(std::string_view field, double value) {
  if (!std::isfinite(value)) {
    throw ParameterError(std::string(field), "must be a finite number (got " + refusal_number(value) + ")");
  }
}

void require_positive(std::string_view field, double value) {
  require_finite(field, value);
  if (!(value > 0.0)) {
    throw ParameterError(std::string(field), "must be > 0 (got " + refusal_number(value) + ")");
  }
}

void require_non_negative(std::string_view field, double value) {
  require_finite(field, value);
  if (value < 0.0) {
    throw ParameterError(std::string(field), "must be >= 0 (got " + refusal_number(value) + ")");
  }
}

void require_in_range(std::string_view field, double value, double lo, double hi) {
  require_finite(field, value);
  if (value < lo || value > hi) {
    throw ParameterError(std::string(field), "must be in [" + refusal_number(lo) + ", " + refusal_number(hi) +
                                                 "] (got " + refusal_number(value) + ")");
  }
}

std::string choice_list(std::span<const std::string_view> choices) {
  std::string out;
  for (std::size_t i = 0; i < choices.size(); ++i) {
    if (i > 0) out += i + 1 == choices.size() ? " or " : ", ";
    out += choices[i];
  }
  return out;
}

}  // namespace hystloop
