#pragma once
// What a refusal names. thrown<E>: runs `f`, returns a copy of the E it throws (nothing when it
// returns; anything else it throws goes on). refused_field: expects `f` to throw ParameterError,
// returns the error's field ("" and a test failure when nothing or something else was thrown).
// config_refusal: runs `f` (typically loading settings from a YAML text), returns the message of
// the ConfigError it throws, or "accepted" when it throws none; a test compares it with what the
// refusal must say, or with "accepted".

#include <gtest/gtest.h>

#include <exception>
#include <optional>
#include <string>

#include "core/config.hpp"
#include "core/errors.hpp"

namespace hystloop::testing {

template <class E, class F>
std::optional<E> thrown(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e;
  }
  return std::nullopt;
}

template <class F>
std::string refused_field(F&& f) {
  try {
    if (const std::optional<ParameterError> e = thrown<ParameterError>(f)) return e->field();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected ParameterError, got: " << e.what();
    return "";
  }
  ADD_FAILURE() << "expected ParameterError, nothing was thrown";
  return "";
}

template <class F>
std::string config_refusal(F&& f) {
  const std::optional<ConfigError> e = thrown<ConfigError>(f);
  return e ? e->what() : "accepted";
}

}  // namespace hystloop::testing
