// The plausible gain band (models/gain_plausibility.hpp): each model's small-signal gain over the
// actuator's range, the band's edges accepted and just beyond them refused naming the field, the
// absurd values an outside probe sent (MEM c2 = 1e300, c1 = 2.9e-322, every gain x1000), and the
// sets the rig is deployed with inside it.
#include "models/gain_plausibility.hpp"
#include "models/model_set.hpp"

#include <gtest/gtest.h>

#include <string>

#include "core/errors.hpp"

namespace hystloop {
namespace {

// The deployed rig: the linear model's 6.34e-9 m/V, +-250 V, F = 10.
GainPlausibility rig() { return GainPlausibility{}; }

ModelParamSet mem(double c1, double c2, double c3) {
  ModelParamSet s;
  s.kind = ModelKind::mem;
  s.mem = {c1, c2, c3};
  return s;
}

ModelParamSet linear(double gain) {
  ModelParamSet s;
  s.kind = ModelKind::linear;
  s.linear = {gain, 0.0};
  return s;
}

ModelParamSet pi15(double scale = 1.0) {
  ModelParamSet s;
  s.kind = ModelKind::pi;
  s.pi = pi_params_from_mem(MemParams::paper_like(), 15, 250.0);
  for (std::size_t i = 0; i < s.pi.count; ++i) s.pi.weights[i] *= scale;
  return s;
}

ModelParamSet katalenic(double output_gain_m_per_V) {
  ModelParamSet s;
  s.kind = ModelKind::katalenic;
  s.katalenic.output_shaping = ShapingFunction::make_linear(output_gain_m_per_V);
  return s;
}

// The refusal's text, "" when accepted.
std::string refusal(const ModelParamSet& set, const GainPlausibility& r = rig()) {
  try {
    require_plausible(set, r);
    return "";
  } catch (const ParameterError& e) {
    return e.what();
  }
}

std::string refused_field(const ModelParamSet& set, const GainPlausibility& r = rig()) {
  try {
    require_plausible(set, r);
    return "";
  } catch (const ParameterError& e) {
    return e.field();
  }
}

TEST(GainPlausibility, EachModelsGainOverTheRange) {
  const GainRange m = small_signal_gain(mem(2e-9, 2e-9, 0.2), rig());
  EXPECT_DOUBLE_EQ(m.min_m_per_V, 2e-9);
  EXPECT_NEAR(m.max_m_per_V, 2e-9 + 2e-9 * std::pow(500.0, 0.2), 1e-18);  // p = u_max - u_min
  const GainRange l = small_signal_gain(linear(6e-9), rig());
  EXPECT_EQ(l.min_m_per_V, 6e-9);
  EXPECT_EQ(l.max_m_per_V, 6e-9);
  // PI: w_0 right after a reversal, the sum of the weights once every play has engaged.
  const ModelParamSet p = pi15();
  double sum = 0.0;
  for (std::size_t i = 0; i < p.pi.count; ++i) sum += p.pi.weights[i];
  const GainRange g = small_signal_gain(p, rig());
  EXPECT_DOUBLE_EQ(g.min_m_per_V, p.pi.weights[0]);
  EXPECT_NEAR(g.max_m_per_V, sum, 1e-20);
  // Katalenic with linear shaping: gain_out / (1 + 2 k1 k2) .. gain_out (k1 40, k2 0.01: / 1.8).
  const GainRange k = small_signal_gain(katalenic(3.79e-9), rig());
  EXPECT_NEAR(k.min_m_per_V, 3.79e-9 / 1.8, 1e-20);
  EXPECT_NEAR(k.max_m_per_V, 3.79e-9, 1e-20);
}

TEST(GainPlausibility, TheBandsEdgesAreAcceptedAndJustBeyondRefusedNamingTheField) {
  const GainPlausibility r = rig();
  EXPECT_EQ(refusal(linear(r.max_gain_m_per_V()), r), "");
  EXPECT_EQ(refusal(linear(r.min_gain_m_per_V()), r), "");
  EXPECT_EQ(refused_field(linear(r.max_gain_m_per_V() * 1.001), r), "linear.gain");
  EXPECT_EQ(refused_field(linear(r.min_gain_m_per_V() * 0.999), r), "linear.gain");
  const std::string why = refusal(linear(r.max_gain_m_per_V() * 1.001), r);
  EXPECT_NE(why.find("6.34e-08"), std::string::npos) << why;     // the bound
  EXPECT_NE(why.find("6.34634e-08"), std::string::npos) << why;  // the value
  EXPECT_NE(why.find("units error"), std::string::npos) << why;  // why
  // MEM: c1 is the gain right after a reversal, the growth c2 p^c3 is taken at the whole range.
  EXPECT_EQ(refused_field(mem(0.99 * r.min_gain_m_per_V(), 0.0, 1.0), r), "mem.c1");
  EXPECT_EQ(refused_field(mem(1.01 * r.max_gain_m_per_V(), 0.0, 1.0), r), "mem.c1");
  const double c2_edge = (r.max_gain_m_per_V() - 2e-9) / 500.0;  // c3 = 1: the slope at 500 V
  EXPECT_EQ(refusal(mem(2e-9, 0.999 * c2_edge, 1.0), r), "");
  EXPECT_EQ(refused_field(mem(2e-9, 1.001 * c2_edge, 1.0), r), "mem.c2");
  // A wider actuator runs longer branches: the same set is then refused.
  GainPlausibility wide = r;
  wide.u_min_V = -500.0;
  wide.u_max_V = 500.0;
  EXPECT_EQ(refused_field(mem(2e-9, 0.999 * c2_edge, 1.0), wide), "mem.c2");
  // A wider factor takes it again.
  wide.factor = 20.0;
  EXPECT_EQ(refusal(mem(2e-9, 0.999 * c2_edge, 1.0), wide), "");
}

TEST(GainPlausibility, TheProbesAbsurdSetsAreRefused) {
  EXPECT_EQ(refused_field(mem(2e-9, 1e300, 0.2)), "mem.c2");
  const std::string tiny = refusal(mem(2.9e-322, 2e-9, 0.2));
  EXPECT_NE(tiny.find("mem.c1"), std::string::npos) << tiny;
  EXPECT_NE(tiny.find("subnormal"), std::string::npos) << tiny;
  // A subnormal that would not change the gain is refused all the same (it costs the tick).
  EXPECT_EQ(refused_field(mem(2e-9, 1e-320, 0.2)), "mem.c2");
  // A units error (y in mm): every gain 1000x.
  const MemParams deployed{1.985e-9, 2.032e-9, 0.2001};
  EXPECT_EQ(refused_field(mem(1e3 * deployed.c1, 1e3 * deployed.c2, deployed.c3)), "mem.c1");
  EXPECT_EQ(refused_field(linear(1e3 * 6.34e-9)), "linear.gain");
  EXPECT_EQ(refused_field(pi15(1e3)), "pi.weights[0]");
  EXPECT_EQ(refused_field(katalenic(1e3 * 3.79e-9)), "katalenic.output_shaping");
  EXPECT_EQ(refused_field(pi15(1e-3)), "pi.weights[0]");
  // A weight that turns the loading curve implausibly steep later on names that play.
  ModelParamSet steep = pi15();
  steep.pi.weights[7] = 1e-6;
  EXPECT_EQ(refused_field(steep), "pi.weights[7]");
  // A set outside its model's own domain keeps its own reason.
  EXPECT_EQ(refused_field(mem(-1e-9, 0.0, 1.0)), "mem.c1");
  EXPECT_NE(refusal(mem(-1e-9, 0.0, 1.0)).find("must be > 0"), std::string::npos);
}

TEST(GainPlausibility, TheSetsTheRigRunsWithAreInside) {
  EXPECT_EQ(refusal(mem(1.985e-9, 2.032e-9, 0.2001)), "");  // deploy/config/compensator.yaml
  EXPECT_EQ(refusal(mem(1.2e-9, 3.6e-9, 0.2)), "");         // deploy/config/demo
  const MemParams paper = MemParams::paper_like();
  EXPECT_EQ(refusal(mem(paper.c1, paper.c2, paper.c3)), "");
  EXPECT_EQ(refusal(pi15()), "");
  EXPECT_EQ(refusal(katalenic(3.79e-9)), "");
  EXPECT_EQ(refusal(linear(6.34e-9)), "");
  // The stage is a unit-gain dynamic part: nothing to bound, whatever it is.
  ModelParamSet staged = linear(6.34e-9);
  staged.stage = StageModel{};
  EXPECT_EQ(refusal(staged), "");
}

TEST(GainPlausibility, TheBandItselfIsValidated) {
  GainPlausibility r;
  EXPECT_NO_THROW(r.validate());
  r.factor = 1.0;
  EXPECT_THROW(r.validate(), ParameterError);
  r = GainPlausibility{};
  r.nominal_gain_m_per_V = -6e-9;
  EXPECT_THROW(r.validate(), ParameterError);
  r = GainPlausibility{};
  r.u_max_V = r.u_min_V;
  EXPECT_THROW(r.validate(), ParameterError);
}

}  // namespace
}  // namespace hystloop
