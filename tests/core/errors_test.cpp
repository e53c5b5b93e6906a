#include "core/errors.hpp"

#include <gtest/gtest.h>

#include <string_view>
#include <vector>

#include <limits>

namespace hystloop {
namespace {

TEST(Errors, MessageNamesTheFieldAndTheValue) {
  try {
    require_positive("stage.k_per_s2", -3.5e-9);
    FAIL() << "expected ParameterError";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "stage.k_per_s2");
    EXPECT_NE(std::string(e.what()).find("-3.5e-09"), std::string::npos) << e.what();
  }
}

TEST(Errors, RefusesNonFiniteEverywhere) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_THROW(require_finite("x", nan), ParameterError);
  EXPECT_THROW(require_positive("x", inf), ParameterError);
  EXPECT_THROW(require_non_negative("x", nan), ParameterError);
  EXPECT_THROW(require_in_range("x", nan, 0.0, 1.0), ParameterError);
}

TEST(Errors, AcceptsBoundaries) {
  EXPECT_NO_THROW(require_non_negative("x", 0.0));
  EXPECT_THROW(require_positive("x", 0.0), ParameterError);
  EXPECT_NO_THROW(require_in_range("x", 1.0, 0.0, 1.0));
  EXPECT_THROW(require_in_range("x", 1.0000001, 0.0, 1.0), ParameterError);
}

TEST(ChoiceList, ListsWhatIsAcceptedWithOrBeforeTheLast) {
  using V = std::vector<std::string_view>;
  EXPECT_EQ(choice_list(V{}), "");
  EXPECT_EQ(choice_list(V{"mem"}), "mem");
  EXPECT_EQ(choice_list(V{"mem", "pi"}), "mem or pi");
  EXPECT_EQ(choice_list(V{"off", "linear", "mem"}), "off, linear or mem");
}

}  // namespace
}  // namespace hystloop
