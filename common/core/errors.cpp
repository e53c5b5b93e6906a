#include "core/errors.hpp"

#include <cmath>
#include <cstdio>

namespace hystloop {
std::string number_text(double v, int significant) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", significant, v);
  return buf;
}

void require_finite(std::string_view field, double value) {
  if (!std::isfinite(value)) {
    throw ParameterError(std::string(field), "must be a finite number (got " + number_text(value) + ")");
  }
}

void require_positive(std::string_view field, double value) {
  require_finite(field, value);
  if (!(value > 0.0)) {
    throw ParameterError(std::string(field), "must be > 0 (got " + number_text(value) + ")");
  }
}

void require_non_negative(std::string_view field, double value) {
  require_finite(field, value);
  if (value < 0.0) {
    throw ParameterError(std::string(field), "must be >= 0 (got " + number_text(value) + ")");
  }
}

void require_in_range(std::string_view field, double value, double lo, double hi) {
  require_finite(field, value);
  if (value < lo || value > hi) {
    throw ParameterError(std::string(field), "must be in [" + number_text(lo) + ", " + number_text(hi) + "] (got " +
                                                 number_text(value) + ")");
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
