// The coupling of the simulated XY(Z) stage identified as a lab would: one axis at a time driven
// through its hysteretic, resonant Banning stage, every axis's sensor recorded (1 nm noise each),
// fit_coupling on the records. The coupling acts on the displacements, so the excited axis's own
// reading stands in for its displacement through hysteresis and dynamics alike: the fit must find
// the configured matrix within its standard errors, and decoupling with it must leave a residual
// coupling of that order.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "ident/coupling_fit.hpp"
#include "loop/multi_axis_stage.hpp"
#include "support/typical_coupling.hpp"

namespace hystloop {
namespace {

constexpr double kDt = 1e-4;          // [s] the loop's tick
constexpr std::size_t kTicks = 8000;  // 0.8 s: four periods of the 5 Hz triangle

double triangle_V(std::size_t k) {  // +-100 V at 5 Hz
  const double phase = std::fmod(5.0 * static_cast<double>(k) * kDt, 1.0);
  return 100.0 * (phase < 0.5 ? 4.0 * phase - 1.0 : 3.0 - 4.0 * phase);
}

// Records every axis while `moved` follows the triangle and the others hold 0 V.
std::array<std::vector<double>, kMaxAxes> excite(MultiAxisStage& stage, int moved) {
  std::array<std::vector<double>, kMaxAxes> y;
  std::array<double, kMaxAxes> u{}, reading{};
  for (std::size_t k = 0; k < kTicks; ++k) {
    u[static_cast<std::size_t>(moved)] = triangle_V(k);
    stage.step(std::span<const double>(u.data(), static_cast<std::size_t>(stage.axes())), static_cast<double>(k) * kDt,
               kDt, std::span<double>(reading.data(), static_cast<std::size_t>(stage.axes())));
    for (int j = 0; j < stage.axes(); ++j)
      y[static_cast<std::size_t>(j)].push_back(reading[static_cast<std::size_t>(j)]);
  }
  return y;
}

TEST(XyCouplingIdentification, RecoversTheSimulatedStagesCoupling) {
  const AxisMatrix truth = testing::typical_coupling();
  MultiAxisStageConfig config = flexure_stage(3);
  config.coupling = AxisCoupling(3, truth);
  // One stage per experiment, as a lab restarts from rest between them.
  std::array<std::array<std::vector<double>, kMaxAxes>, kMaxAxes> records;
  std::vector<AxisExcitation> experiments;
  for (int i = 0; i < 3; ++i) {
    for (std::size_t j = 0; j < 3; ++j)
      config.axis[j].seed = 10 * static_cast<std::uint64_t>(i) + j + 1;  // fresh noise
    MultiAxisStage stage(config);
    records[static_cast<std::size_t>(i)] = excite(stage, i);
    AxisExcitation e;
    e.axis = i;
    for (int j = 0; j < 3; ++j)
      e.y_m[static_cast<std::size_t>(j)] = records[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)];
    experiments.push_back(e);
  }
  const CouplingFitResult r = fit_coupling(experiments);
  ASSERT_TRUE(r.ok()) << r.reason;
  double worst_in_se = 0.0, worst_se = 0.0;
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      if (i == j) continue;
      const double se = r.standard_error(j, i);
      ASSERT_GT(se, 0.0);
      ASSERT_LT(se, 2e-4)
          << "the +-100 V triangle moves each axis ~1.4 um peak to peak: 1 nm of noise is ~1e-5 of its spread";
      worst_in_se = std::max(worst_in_se, std::fabs(r.estimate(j, i) - truth(j, i)) / se);
      worst_se = std::max(worst_se, se);
    }
  }
  const AxisMatrix residual = truth * r.coupling.inverse_matrix() - AxisMatrix::Identity();
  std::printf(
      "worst entry error %.2f standard errors (worst standard error %.2e); residual coupling after "
      "decoupling %.2e (before 3.0e-02)\n",
      worst_in_se, worst_se, residual.cwiseAbs().maxCoeff());
  EXPECT_LT(worst_in_se, 3.5);
  EXPECT_LT(residual.cwiseAbs().maxCoeff(), 2e-4) << residual;  // from 3e-2 before decoupling
}

}  // namespace
}  // namespace hystloop
