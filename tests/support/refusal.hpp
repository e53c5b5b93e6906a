#pragma once
// What a refusal names. refused_field: runs `f`, expects it to throw ParameterError, returns the
// error's field ("" and a test failure when nothing or something else was thrown).
// config_refusal: runs `f` (typically loading settings from a YAML text), returns the message of
// the ConfigError it throws, or "accepted" when it throws none; a test compares it with what the
// refusal must say, or with "accepted".

#include <gtest/gtest.h>

#include <string>

#include "core/config.hpp"
#include "core/errors.hpp"

namespace hystloop::testing {

template <class F>
std::string refused_field(F&& f) {
  try {
    f();
  } catch (const ParameterError& e) {
    return e.field();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected ParameterError, got: " << e.what();
    return "";
  }
  ADD_FAILURE() << "expected ParameterError, nothing was thrown";
  return "";
}

template <class F>
std::string config_refusal(F&& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "accepted";
}

}  // namespace hystloop::testing
