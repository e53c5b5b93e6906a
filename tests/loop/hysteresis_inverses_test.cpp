#include "loop/hysteresis_inverses.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>

namespace hystloop {
namespace {

HysteresisInverses make() {
  const MemParams mem = MemParams::paper_like();
  return HysteresisInverses(ModelParams{.mem = mem, .pi = pi_params_from_mem(mem, 15, 250.0)});
}

constexpr ModelKind kKinds[] = {ModelKind::mem, ModelKind::pi, ModelKind::katalenic, ModelKind::linear};

// Restarted at a reversal, every inverse answers the output it returned with the reversal's own
// voltage: the swap of parameters or model there makes no step in u.
TEST(HysteresisInverses, ARestartAtAReversalMakesNoStepInTheVoltage) {
  for (const ModelKind kind : kKinds) {
    SCOPED_TRACE(to_string(kind));
    HysteresisInverses inverses = make();
    inverses.start(kind, 0.0, std::nullopt);
    const double u_prev = -80.0, u_rev = 120.0;
    // MEM starts its branch at the target it is given; the others at their own output there.
    const double w = kind == ModelKind::mem ? 0.4e-6 : std::numeric_limits<double>::quiet_NaN();
    const double y = inverses.restart_at_reversal(kind, u_prev, u_rev, w);
    ASSERT_TRUE(std::isfinite(y));
    if (kind == ModelKind::mem) {
      EXPECT_EQ(y, w);
    }
    EXPECT_NEAR(inverses.inverse(kind, y), u_rev, 1e-6);
  }
}

// A moved stage is continued where it was measured by MEM (no jump in u); the others start at y0.
TEST(HysteresisInverses, MemContinuesAMeasuredBranchTheOthersStartAtTheReference) {
  HysteresisInverses inverses = make();
  const StagePoint at{100.0, 0.5e-6, -100.0};
  inverses.start(ModelKind::mem, 0.0, at);
  EXPECT_NEAR(inverses.inverse(ModelKind::mem, at.y_m), at.u_V, 1e-9);
  inverses.start(ModelKind::linear, 0.3e-6, at);
  EXPECT_NEAR(inverses.inverse(ModelKind::linear, 0.3e-6), 0.3e-6 / LinearParams{}.gain, 1e-9);
}

TEST(HysteresisInverses, ParametersGoToTheModelTheSetNamesAndComeBackForAll) {
  HysteresisInverses inverses = make();
  ModelParamSet set;
  set.kind = ModelKind::linear;
  set.linear.gain = 7e-9;
  set.mem.c1 = 123.0;  // not the kind named: ignored
  inverses.set_params(set);
  ModelParamSet all;
  inverses.get_params(all);
  EXPECT_EQ(all.linear.gain, 7e-9);
  EXPECT_EQ(all.mem.c1, MemParams::paper_like().c1);
  EXPECT_EQ(inverses.nominal_slope(ModelKind::mem), MemParams::paper_like().c1);
  EXPECT_EQ(inverses.nominal_slope(ModelKind::pi), all.pi.weights[0]);
  EXPECT_EQ(inverses.nominal_slope(ModelKind::katalenic), 7e-9);  // no single slope: the line's
  HysteresisInverses other = make();
  other.take_params_from(inverses);
  EXPECT_EQ(other.linear_params().gain, 7e-9);
}

}  // namespace
}  // namespace hystloop
