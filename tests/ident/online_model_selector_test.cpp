// The online model choice: a known-best model wins, a tie keeps the model in use, a worse
// candidate is never proposed, pinned never changes the model, proposals are always valid.
#include "ident/online_model_selector.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "core/errors.hpp"
#include "ident/mem_test_data.hpp"

namespace hystloop {
namespace {

// A 100 Hz line at 10 kHz decimated by 10: every 10th sample misses the peaks (ticks 48 and 98
// of each 100 here), the decimation that keeps extremes has each peak exactly, u is monotone
// between any two kept samples, and it keeps no more than two samples a reversal beyond every
// 10th (and the last).
TEST(DecimateKeepingExtremes, KeepsEveryNthAndEachPeak) {
  std::vector<double> u(2000);
  for (std::size_t k = 0; k < u.size(); ++k) {
    u[k] = 75.0 * std::sin(2.0 * std::numbers::pi * (static_cast<double>(k) + 27.0) / 100.0);
  }
  // The peaks: u = +75 at k = 100 j + 98, -75 at 100 j + 48 (a phase off the tens).
  const std::vector<std::size_t> kept = decimate_keeping_extremes(u, 10);
  std::size_t peaks = 0;
  for (const std::size_t k : kept) peaks += std::abs(std::abs(u[k]) - 75.0) < 1e-9 ? 1 : 0;
  EXPECT_EQ(peaks, 40u);  // 20 periods, two peaks each
  for (std::size_t i = 0; i + 2 < kept.size(); ++i) {
    // Between kept samples the path is monotone: no sample beyond the two ends.
    const double lo = std::min(u[kept[i]], u[kept[i + 1]]), hi = std::max(u[kept[i]], u[kept[i + 1]]);
    for (std::size_t k = kept[i] + 1; k < kept[i + 1]; ++k) {
      ASSERT_GE(u[k], lo - 1e-12) << k;
      ASSERT_LE(u[k], hi + 1e-12) << k;
    }
  }
  EXPECT_EQ(kept.size(), 200u + 40u + 1u);
  EXPECT_EQ(kept.back(), u.size() - 1);
  // Every sample without decimation; nothing from nothing.
  EXPECT_EQ(decimate_keeping_extremes(u, 1).size(), u.size());
  EXPECT_TRUE(decimate_keeping_extremes(std::vector<double>{}, 10).empty());
}

// 4 s of a 1 Hz, 200 V sine at 1 kHz (eight branches, as the tracking loop's window holds).
std::vector<double> window_input() { return testdata::sine_input(200.0, 1.0, 1e3, 4.0); }

template <class Model>
std::vector<double> respond(Model& model, const std::vector<double>& u, double noise_m, std::uint64_t seed) {
  std::vector<double> y(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) y[k] = model.forward(u[k]);
  testdata::add_noise(y, noise_m, seed);
  return y;
}

ModelParamSet mem_set(const MemParams& p) {
  ModelParamSet s;
  s.kind = ModelKind::mem;
  s.mem = p;
  return s;
}

void print(const ModelProposal& p) {
  std::printf("%s: %s\n", std::string(to_string(p.kind)).c_str(), p.reason.c_str());
}

// A stage whose slope saturates a short way after each reversal (the plays beyond r_2 carry no
// weight), as Coleman-Hodgdon's does: PI describes it, MEM's unbounded power law cannot.
PiParams saturating_pi() {
  PiParams p = PiParams::with_even_thresholds(15, 250.0);
  p.weights[0] = 2e-9;
  p.weights[1] = 3e-9;
  p.weights[2] = 1.5e-9;
  return p;
}

TEST(OnlineModelSelector, AKnownBestModelWins) {
  // A Ramberg-Osgood stage, the linear feedforward in use: MEM is exact and wins by far.
  MemModel stage(MemParams::paper_like());
  stage.reset(0.0);
  const auto u = window_input();
  const auto y = respond(stage, u, 1e-9, 3);
  ModelParamSet in_use;
  in_use.kind = ModelKind::linear;
  in_use.linear = linear_params_from_mem(MemParams::paper_like(), 200.0);
  const ModelProposal p = propose_model(u, y, in_use);
  print(p);
  ASSERT_TRUE(p.status == FitStatus::ok) << p.reason;
  EXPECT_EQ(p.kind, ProposalKind::model_change);
  EXPECT_EQ(p.winner, ModelKind::mem);
  ASSERT_EQ(p.params.kind, ModelKind::mem);
  EXPECT_NO_THROW(p.params.validate());
  EXPECT_NEAR(p.params.mem.c1, MemParams::paper_like().c1, 0.02 * MemParams::paper_like().c1);
  EXPECT_LT(p.winner_holdout_rms_m, 0.9 * p.in_use_holdout_rms_m);
}

TEST(OnlineModelSelector, ASaturatingStageLeavesMem) {
  // MEM in use on a stage whose slope saturates: a model with saturating slopes is proposed.
  PiModel stage(saturating_pi());
  stage.reset(0.0);
  const auto u = window_input();
  const auto y = respond(stage, u, 1e-9, 3);
  const ModelProposal p = propose_model(u, y, mem_set(MemParams::paper_like()));
  print(p);
  ASSERT_TRUE(p.status == FitStatus::ok) << p.reason;
  EXPECT_EQ(p.kind, ProposalKind::model_change);
  EXPECT_TRUE(p.params.kind == ModelKind::pi || p.params.kind == ModelKind::katalenic);
  EXPECT_LT(p.winner_holdout_rms_m, 0.9 * std::min(p.in_use_holdout_rms_m, p.in_use_refit_holdout_rms_m));
}

TEST(OnlineModelSelector, PinnedRefitsButNeverChangesTheModel) {
  const PiParams truth = saturating_pi();
  PiModel stage(truth);
  stage.reset(0.0);
  const auto u = window_input();
  const auto y = respond(stage, u, 1e-9, 3);
  MemParams wrong = MemParams::paper_like();
  wrong.c1 *= 0.6;
  OnlineSelectorOptions o;
  o.pinned = true;
  const ModelProposal p = propose_model(u, y, mem_set(wrong), o);
  print(p);
  EXPECT_NE(p.kind, ProposalKind::model_change);
  EXPECT_EQ(p.kind, ProposalKind::refit);  // the wrong MEM set is refitted
  EXPECT_EQ(p.params.kind, ModelKind::mem);
}

TEST(OnlineModelSelector, ATieKeepsTheModelInUse) {
  // A Ramberg-Osgood stage with PI-15 in use, fitted to the same curve: MEM is exact, PI-15 within
  // a few per cent of it. Not by the margin: PI stays.
  MemModel mem_stage(MemParams::paper_like());
  mem_stage.reset(0.0);
  const auto u_mem = window_input();
  const auto y_mem = respond(mem_stage, u_mem, 1e-9, 9);
  ModelParamSet pi_in_use;
  pi_in_use.kind = ModelKind::pi;
  pi_in_use.pi = pi_params_from_mem(MemParams::paper_like(), 15, 200.0);
  const ModelProposal tie = propose_model(u_mem, y_mem, pi_in_use);
  print(tie);
  ASSERT_TRUE(tie.status == FitStatus::ok) << tie.reason;
  EXPECT_NE(tie.kind, ProposalKind::model_change);
  EXPECT_GE(tie.winner_holdout_rms_m, 0.9 * std::min(tie.in_use_holdout_rms_m, tie.in_use_refit_holdout_rms_m));
}

TEST(OnlineModelSelector, ALinearStageKeepsTheLinearSet) {
  // A linear stage: every model describes it (MEM with c2 -> 0, PI with one play), none by a
  // margin over the exact linear set in use.
  LinearParams truth;
  truth.gain = 6e-9;
  LinearModel stage(truth);
  const auto u = window_input();
  const auto y = respond(stage, u, 1e-9, 5);
  ModelParamSet in_use;
  in_use.kind = ModelKind::linear;
  in_use.linear = truth;
  const ModelProposal p = propose_model(u, y, in_use);
  print(p);
  ASSERT_TRUE(p.status == FitStatus::ok) << p.reason;
  EXPECT_NE(p.kind, ProposalKind::model_change);
}

TEST(OnlineModelSelector, AWorseCandidateIsNeverProposed) {
  // A Ramberg-Osgood (MEM) stage with MEM's exact set in use: nothing beats it.
  const MemParams truth = MemParams::paper_like();
  MemModel stage(truth);
  stage.reset(0.0);
  const auto u = window_input();
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const auto y = respond(stage, u, 1e-9, seed);
    const ModelProposal p = propose_model(u, y, mem_set(truth));
    print(p);
    ASSERT_TRUE(p.status == FitStatus::ok) << p.reason;
    EXPECT_NE(p.kind, ProposalKind::model_change);
    if (p.proposes()) {
      EXPECT_EQ(p.params.kind, ModelKind::mem);
      EXPECT_LT(p.in_use_refit_holdout_rms_m, p.in_use_holdout_rms_m);
    }
  }
}

TEST(OnlineModelSelector, RefusesBadOptionsAndShortWindows) {
  const auto u = testdata::sine_input(200.0, 1.0, 1e3, 1.0);  // two branches: too few
  std::vector<double> y(u.size(), 0.0);
  const ModelProposal p = propose_model(u, y, mem_set(MemParams::paper_like()));
  EXPECT_FALSE(p.proposes());
  EXPECT_EQ(p.status, FitStatus::too_few_branches) << p.reason;
  OnlineSelectorOptions bad;
  bad.margin = -0.1;
  EXPECT_THROW(propose_model(u, y, mem_set(MemParams::paper_like()), bad), ParameterError);
  bad = {};
  bad.decimation = 0;
  EXPECT_THROW(propose_model(u, y, mem_set(MemParams::paper_like()), bad), ParameterError);
  MemParams invalid;
  invalid.c1 = -1.0;
  EXPECT_THROW(propose_model(u, y, mem_set(invalid)), ParameterError);
}

}  // namespace
}  // namespace hystloop
