#pragma once
// The field a refused value names: runs `f`, expects it to throw ParameterError, returns the
// error's field ("" and a test failure when nothing or something else was thrown).

#include <gtest/gtest.h>

#include <string>

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

}  // namespace hystloop::testing
