// Model selection ranks by held-out prediction error.
#include "ident/model_selection.hpp"

#include <gtest/gtest.h>

#include <cstdio>

#include "core/errors.hpp"
#include "ident/mem_test_data.hpp"

namespace hystloop {
namespace {

TEST(ModelSelection, MemDataRanksMemFirstAndLinearLast) {
  const MemParams truth = MemParams::paper_like();
  const auto u = testdata::paper_identification_input();
  std::vector<double> y = testdata::model_output(truth, u);
  testdata::add_noise(y, 1e-9, 17);
  const ModelSelection sel = select_model(u, y);
  ASSERT_TRUE(sel.ok()) << sel.reason;
  ASSERT_EQ(sel.ranking.size(), 4u);
  for (const auto& s : sel.ranking) {
    std::printf("%-10s %-8s train %.3g nm  held-out %.3g nm  %.1f ms\n", std::string(to_string(s.kind)).c_str(),
                std::string(to_string(s.status)).c_str(), s.train_rms_m * 1e9, s.holdout_rms_m * 1e9,
                s.fit_time_s * 1e3);
  }
  EXPECT_EQ(sel.ranking.front().kind, ModelKind::mem);
  EXPECT_EQ(sel.ranking.back().kind, ModelKind::linear);
  EXPECT_LT(sel.ranking.front().holdout_rms_m, 1.5e-9);  // ~ the sensor noise
  EXPECT_GT(sel.split_index, u.size() / 2);
}

TEST(ModelSelection, RefusesARecordWithoutEnoughBranches) {
  std::vector<double> u(1000), y(1000);
  for (std::size_t k = 0; k < u.size(); ++k) u[k] = static_cast<double>(k), y[k] = 1e-9 * u[k];
  const ModelSelection sel = select_model(u, y);
  EXPECT_EQ(sel.status, FitStatus::too_few_branches) << sel.reason;
  EXPECT_FALSE(sel.reason.empty());
  ModelSelectionOptions bad;
  bad.holdout_fraction = 0.99;
  EXPECT_THROW(select_model(u, y, bad), ParameterError);
}

}  // namespace
}  // namespace hystloop
