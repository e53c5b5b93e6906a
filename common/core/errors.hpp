#pragma once
// Errors raised at the boundary: configuration and parameters that are refused
// before they can reach a model or the actuator. Inside the per-sample loop
// nothing throws; a status value leads to a safe state instead.

#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

namespace hystloop {

// A parameter or configuration value that was refused. `field()` names it
// (e.g. "c3", "mem.c3", "bridge.u_max_V") so the user can find it in the file.
class ParameterError : public std::invalid_argument {
 public:
  ParameterError(std::string field, const std::string& reason)
      : std::invalid_argument(field + ": " + reason), field_(std::move(field)), reason_(reason) {}
  const std::string& field() const noexcept { return field_; }
  const std::string& reason() const noexcept { return reason_; }  // what() without "field: "

 private:
  std::string field_;
  std::string reason_;
};

// Runs validate(); a ParameterError from it is thrown again with `prefix` before its field
// ("c3" -> "mem.c3"), so a nested set's refusal names the field as the file spells it.
template <class Validate>
void validate_within(std::string_view prefix, Validate&& validate) {
  try {
    validate();
  } catch (const ParameterError& e) {
    throw ParameterError(std::string(prefix) + e.field(), e.reason());
  }
}

// A number for a message, a table or a file: printf's "%.<significant>g" (8.58e-09, 250, inf), which
// keeps SI values such as 8.58e-09 m/V readable where std::to_string would print 0.000000.
std::string number_text(double v, int significant = 6);

// Throws ParameterError unless `value` is finite.
void require_finite(std::string_view field, double value);
// Throws ParameterError unless `value` is finite and > 0.
void require_positive(std::string_view field, double value);
// Throws ParameterError unless `value` is finite and >= 0.
void require_non_negative(std::string_view field, double value);
// Throws ParameterError unless lo <= value <= hi (and finite).
void require_in_range(std::string_view field, double value, double lo, double hi);

// "a, b or c": what a refusal lists as accepted ("" for none, "a" for one).
std::string choice_list(std::span<const std::string_view> choices);

}  // namespace hystloop
