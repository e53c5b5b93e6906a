// Static linear model (the paper's linear-spring feedforward): forward/inverse, validation, the
// MEM-derived gain and the bumpless swap.

#include "models/linear.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/errors.hpp"
#include "models/mem.hpp"
#include "models/model_concepts.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

static_assert(HysteresisForward<LinearModel>);
static_assert(HysteresisInverse<LinearInverse>);

TEST(Linear, ForwardAndInverse) {
  const LinearParams p{6e-9, 1e-7};
  LinearModel f(p);
  LinearInverse inv(p);
  EXPECT_DOUBLE_EQ(f.forward(100.0), 6e-7 + 1e-7);
  EXPECT_DOUBLE_EQ(inv.inverse(7e-7), 100.0);
  testing::AllocationCounter counter;
  for (double u = -250.0; u <= 250.0; u += 0.37) EXPECT_NEAR(inv.inverse(f.forward(u)), u, 1e-12);
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_TRUE(std::isnan(f.forward(std::numeric_limits<double>::infinity())));
}

TEST(Linear, ValidationNamesTheField) {
  auto field_of = [](const LinearParams& p) {
    try {
      p.validate();
    } catch (const ParameterError& e) {
      return e.field();
    }
    return std::string("accepted");
  };
  EXPECT_EQ(field_of({0.0, 0.0}), "gain");
  EXPECT_EQ(field_of({std::numeric_limits<double>::quiet_NaN(), 0.0}), "gain");
  EXPECT_EQ(field_of({1e-9, std::numeric_limits<double>::infinity()}), "offset");
  EXPECT_EQ(field_of({-1e-9, 0.0}), "accepted");  // an inverted sensor is still invertible
  EXPECT_THROW(LinearModel(LinearParams{0.0, 0.0}), ParameterError);
  EXPECT_THROW(LinearInverse(LinearParams{0.0, 0.0}), ParameterError);
}

TEST(Linear, FromMemIsTheMajorLoopChord) {
  const MemParams mem = MemParams::paper_like();
  const LinearParams p = linear_params_from_mem(mem, 250.0);
  EXPECT_NEAR(p.gain, LinearParams{}.gain, 0.001e-9);  // the documented default
  MemModel model(mem);
  model.forward(-250.0);
  model.forward(249.0);
  const double bottom = model.forward(-250.0);
  const double top = model.forward(250.0);
  EXPECT_NEAR(p.gain, (top - bottom) / 500.0, 1e-20);
}

TEST(Linear, SetParamsKeepsContinuity) {
  LinearModel f(LinearParams{6e-9, 0.0});
  LinearInverse inv(LinearParams{6e-9, 0.0});
  const double y = f.forward(100.0);
  const double u = inv.inverse(y);
  f.set_params({5e-9, 2e-7});
  inv.set_params({5e-9, 2e-7});
  EXPECT_NEAR(f.forward(100.0), y, 1e-21);
  EXPECT_NEAR(f.forward(101.0), y + 5e-9, 1e-21);
  EXPECT_NEAR(inv.inverse(y), u, 1e-12);
  EXPECT_NEAR(inv.inverse(y + 5e-9), u + 1.0, 1e-9);
  f.reset();
  EXPECT_DOUBLE_EQ(f.forward(0.0), 2e-7);
}

}  // namespace
}  // namespace hystloop
