// Axis coupling (models/axis_coupling.hpp): decouple undoes couple, the identity passes values
// through untouched, every refusal names its field, and the per-sample calls allocate nothing.

#include "models/axis_coupling.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <string>

#include "core/errors.hpp"
#include "support/allocation_counter.hpp"
#include "support/refusal.hpp"
#include "support/typical_coupling.hpp"

namespace hystloop {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

AxisMatrix typical() { return testing::typical_coupling(); }

std::optional<ParameterError> refusal(int n, const AxisMatrix& c) {
  return testing::thrown<ParameterError>([&] { AxisCoupling coupling(n, c); });
}
std::string field_of(int n, const AxisMatrix& c) {
  const auto e = refusal(n, c);
  return e ? e->field() : "accepted";
}
std::string reason_of(int n, const AxisMatrix& c) {
  const auto e = refusal(n, c);
  return e ? e->reason() : "accepted";
}

TEST(AxisCoupling, DecoupleUndoesCouple) {
  const AxisCoupling coupling(3, typical());
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> um(-50e-6, 50e-6);
  double worst = 0.0;
  testing::AllocationCounter counter;
  for (int trial = 0; trial < 1000; ++trial) {
    const AxisVector s(um(rng), um(rng), um(rng));
    const AxisVector y = coupling.couple(s);
    const AxisVector w = coupling.decouple(y);
    const AxisVector back = coupling.couple(coupling.decouple(s));
    for (int i = 0; i < 3; ++i) {
      // couple is C s itself, not some other product.
      EXPECT_NEAR(y(i), (typical() * s)(i), 1e-15 * s.norm());
    }
    worst = std::max(worst, (w - s).norm() / s.norm());
    worst = std::max(worst, (back - s).norm() / s.norm());
  }
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_LE(worst, 1e-12);
  // The stored inverse is C^{-1}, and it actually decouples: y = C w = r.
  EXPECT_LE((coupling.inverse_matrix() * typical() - AxisMatrix::Identity()).cwiseAbs().maxCoeff(), 1e-15);
  const AxisVector r(1e-6, -2e-6, 0.5e-6);
  EXPECT_GT((coupling.decouple(r) - r).norm(), 1e-8);  // not the identity
}

TEST(AxisCoupling, DecoupleOnTwoAxesLeavesTheThirdEntryAlone) {
  AxisMatrix c = typical();
  c(2, 0) = kNaN;  // outside the 2x2 block: ignored
  const AxisCoupling coupling(2, c);
  EXPECT_EQ(coupling.n(), 2);
  EXPECT_EQ(coupling.matrix()(2, 0), 0.0);
  const AxisVector r(1e-6, 2e-6, 7.0);
  const AxisVector w = coupling.decouple(r);
  EXPECT_EQ(w(2), 7.0);
  const AxisVector y = coupling.couple(w);
  EXPECT_NEAR(y(0), r(0), 1e-12 * r.norm());
  EXPECT_NEAR(y(1), r(1), 1e-12 * r.norm());
  // By hand: w = C^{-1} r for the 2x2 [1 -0.01; 0.03 1].
  const double det = 1.0 + 0.01 * 0.03;
  EXPECT_NEAR(w(0), (r(0) + 0.01 * r(1)) / det, 1e-20);
  EXPECT_NEAR(w(1), (r(1) - 0.03 * r(0)) / det, 1e-20);
}

TEST(AxisCoupling, IdentityPassesValuesThrough) {
  const AxisCoupling one = AxisCoupling::identity(1);
  EXPECT_EQ(one.n(), 1);
  const AxisVector r(3e-6, kNaN, -1.0);
  const AxisVector w = one.decouple(r);
  EXPECT_EQ(w(0), r(0));
  EXPECT_TRUE(std::isnan(w(1)));
  EXPECT_EQ(w(2), r(2));
  EXPECT_EQ(one.couple(r)(0), r(0));
  EXPECT_DOUBLE_EQ(one.condition_number(), 1.0);
  EXPECT_EQ(one.describe(), "x: single axis, no coupling");
  EXPECT_EQ(AxisCoupling().n(), 1);
  EXPECT_EQ(AxisCoupling().decouple(r)(0), r(0));

  // An uncoupled axis takes nothing from another axis's NaN (0 * NaN would be NaN) ...
  const AxisCoupling three = AxisCoupling::identity(3);
  const AxisVector bad_x(kNaN, 1e-6, -2e-6);
  EXPECT_EQ(three.decouple(bad_x)(1), 1e-6);
  EXPECT_EQ(three.decouple(bad_x)(2), -2e-6);
  // ... while an axis coupled to it does.
  AxisMatrix xy = AxisMatrix::Identity();
  xy(1, 0) = 0.03;
  const AxisCoupling coupled(3, xy);
  const AxisVector w3 = coupled.decouple(bad_x);
  EXPECT_TRUE(std::isnan(w3(0)));
  EXPECT_TRUE(std::isnan(w3(1)));
  EXPECT_EQ(w3(2), -2e-6);
}

TEST(AxisCoupling, RefusalsNameTheField) {
  EXPECT_EQ(field_of(3, typical()), "accepted");

  AxisMatrix c = typical();
  c(1, 1) = 1.02;  // a gain: belongs to axis y's own model
  EXPECT_EQ(field_of(3, c), "coupling[1][1]");
  EXPECT_NE(reason_of(3, c).find("exactly 1"), std::string::npos) << reason_of(3, c);

  c = typical();
  c(2, 0) = 0.6;
  EXPECT_EQ(field_of(3, c), "coupling[2][0]");
  c(2, 0) = 0.5;  // the bound itself is accepted
  EXPECT_EQ(field_of(3, c), "accepted");
  c = typical();
  c(0, 1) = -0.51;
  EXPECT_EQ(field_of(3, c), "coupling[0][1]");

  c = typical();
  c(1, 2) = kNaN;
  EXPECT_EQ(field_of(3, c), "coupling[1][2]");
  c(1, 2) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(field_of(3, c), "coupling[1][2]");

  EXPECT_EQ(field_of(0, typical()), "n");
  EXPECT_EQ(field_of(4, typical()), "n");
  EXPECT_THROW(AxisCoupling::identity(0), ParameterError);
  EXPECT_THROW(AxisCoupling::identity(kMaxAxes + 1), ParameterError);
}

// |C_ji| <= 0.5 still admits a singular 3x3: I + a (J - I) has eigenvalues 1 + 2a and 1 - a
// (twice), so cond = (1 - a) / (1 + 2a) for a < 0.
TEST(AxisCoupling, RefusesANearlySingularCoupling) {
  auto equal = [](double a) {
    AxisMatrix c = AxisMatrix::Constant(a);
    c.diagonal().setOnes();
    return c;
  };
  EXPECT_EQ(field_of(3, equal(-0.5)), "coupling");    // singular
  EXPECT_EQ(field_of(3, equal(-0.499)), "coupling");  // cond 749.5
  EXPECT_NE(reason_of(3, equal(-0.499)).find("condition number 749"), std::string::npos) << reason_of(3, equal(-0.499));
  EXPECT_EQ(field_of(3, equal(-0.495)), "coupling");  // cond 149.5
  EXPECT_EQ(field_of(3, equal(-0.49)), "accepted");   // cond 74.5
  EXPECT_NEAR(AxisCoupling(3, equal(-0.49)).condition_number(), 1.49 / 0.02, 1e-9);
  EXPECT_NEAR(AxisCoupling(3, equal(0.1)).condition_number(), 1.2 / 0.9, 1e-12);
  // The same entries on two axes are harmless: [1 -0.5; -0.5 1] has cond 3.
  EXPECT_NEAR(AxisCoupling(2, equal(-0.5)).condition_number(), 3.0, 1e-12);
}

TEST(AxisCoupling, DescribeIsOneLine) {
  AxisMatrix c = AxisMatrix::Identity();
  c(1, 0) = 0.03;
  c(0, 1) = -0.005;
  EXPECT_EQ(AxisCoupling(2, c).describe(), "x->y 3.0 %, y->x -0.5 %");
  EXPECT_EQ(AxisCoupling(3, typical()).describe(),
            "x->y 3.0 %, x->z 0.5 %, y->x -1.0 %, y->z 1.5 %, z->x 0.8 %, z->y -2.0 %");
  c(1, 0) = -1e-5;  // rounds to zero: printed without a sign
  EXPECT_EQ(AxisCoupling(2, c).describe(), "x->y 0.0 %, y->x -0.5 %");
}

TEST(AxisCoupling, AxisNames) {
  EXPECT_EQ(axis_name(0), "x");
  EXPECT_EQ(axis_name(1), "y");
  EXPECT_EQ(axis_name(2), "z");
  EXPECT_EQ(axis_name(3), "?");
  EXPECT_EQ(axis_name(-1), "?");
}

}  // namespace
}  // namespace hystloop
