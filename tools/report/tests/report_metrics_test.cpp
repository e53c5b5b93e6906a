// report_metrics on hand-made RunData: the definitions the tool's figures rest on.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/errors.hpp"
#include "report_metrics.hpp"

using namespace hystloop;
using namespace hystloop::report;

namespace {

constexpr std::int64_t kT0 = 1'000'000'000;

RunData ramp_run(std::int64_t ticks, std::int64_t tick_us) {
  RunData run;
  for (std::int64_t k = 0; k < ticks; ++k) {
    run.samples.push_back({kT0 + k * tick_us, k, 0.0, 1e-6 + 1e-9 * static_cast<double>(k % 3), 0});
    run.commands.push_back({kT0 + k * tick_us - 10, k, -1, 0.0, 1e-6, 0});
  }
  return run;
}

}  // namespace

TEST(NearestRank, MatchesTheDefinition) {
  EXPECT_FALSE(nearest_rank({}, 0.5));
  const std::vector<double> v{1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  EXPECT_EQ(*nearest_rank(v, 0.0), 1);
  EXPECT_EQ(*nearest_rank(v, 0.5), 5);   // ceil(5) = 5th
  EXPECT_EQ(*nearest_rank(v, 0.51), 6);  // ceil(5.1) = 6th
  EXPECT_EQ(*nearest_rank(v, 0.99), 10);
  EXPECT_EQ(*nearest_rank(v, 1.0), 10);
}

TEST(ReportOptions, RefusesBadRangesNamingTheOption) {
  ReportOptions o;
  o.skip_initial_s = -1;
  try {
    o.validate();
    FAIL();
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "--skip-initial");
  }
  o = {};
  o.from_s = 4;
  o.to_s = 3;
  EXPECT_THROW(o.validate(), ParameterError);
  o.from_s = std::nan("");
  EXPECT_THROW(o.validate(), ParameterError);
  o = {};
  EXPECT_TRUE(std::isinf(o.lower_s()));
  o.skip_initial_s = 2;
  EXPECT_EQ(o.lower_s(), 2.0);
  o.from_s = 1;
  EXPECT_EQ(o.lower_s(), 3.0);
}

TEST(ComputeMetrics, RandomErrorsGiveTheirRms) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 30e-9);
  RunData run;
  double sum = 0;
  for (std::int64_t k = 0; k < 5000; ++k) {
    const double e = noise(rng);
    sum += e * e;
    run.samples.push_back({kT0 + k * 100, k, 0.0, 2e-6 + e, 0});
    run.commands.push_back({kT0 + k * 100 - 50, k, k - 1, 0.0, 2e-6, 3});
  }
  const auto m = compute_metrics(run, {});
  EXPECT_NEAR(*m.rms_error_m, std::sqrt(sum / 5000.0), 1e-18);
  EXPECT_NEAR(*m.rms_error_m, 30e-9, 2e-9);
  ASSERT_EQ(m.per_second.size(), 1u);
  EXPECT_EQ(m.per_second[0].params_version, 3);
  EXPECT_EQ(*m.latency_p50_us, 50.0);  // command k at -50 us, sample k-1 at -100 us
  EXPECT_EQ(m.latencies_us.size(), 4999u);
  EXPECT_EQ(*m.late_command_fraction, 0.0);
}

TEST(ComputeMetrics, EmptySecondsAreListedAndCarryTheVersion) {
  RunData run;
  run.samples.push_back({kT0, 0, 0, 1e-6, 0});
  run.commands.push_back({kT0, 0, -1, 0, 1e-6, 5});
  run.samples.push_back({kT0 + 3'500'000, 1, 0, 1e-6, 0});  // seconds 1 and 2 have nothing
  const auto m = compute_metrics(run, {});
  ASSERT_EQ(m.per_second.size(), 4u);
  EXPECT_EQ(m.per_second[2].tracking_samples, 0u);
  EXPECT_FALSE(m.per_second[2].rms_error_m);
  EXPECT_EQ(m.per_second[3].params_version, 5);
  EXPECT_EQ(m.seq_gaps, 0);
  EXPECT_EQ(m.tracking_samples, 1u);  // sample 1 has no command: not tracking
}

TEST(ComputeMetrics, FirstCommandForATickWinsAndNanMeansNoReference) {
  RunData run = ramp_run(10, 100);
  run.commands.push_back({kT0 + 50, 1, -1, 0, 5e-6, 0});  // a later duplicate for tick 1
  run.commands[2].y_ref_m = std::nan("");                 // tick 2 has no reference
  const auto m = compute_metrics(run, {});
  EXPECT_EQ(m.tracking_samples, 9u);
  EXPECT_NEAR(*m.max_abs_error_m, 2e-9, 1e-18);
}

TEST(ComputeMetrics, NothingArmedGivesNoLateFraction) {
  RunData run = ramp_run(10, 100);
  for (auto& s : run.samples) s.flags = 2 | 16;  // SAFE_STATE | LATE_COMMAND
  const auto m = compute_metrics(run, {});
  EXPECT_EQ(m.armed_samples, 0u);
  EXPECT_FALSE(m.late_command_fraction);
}

TEST(ComputeMetrics, RejectedCommandsFallBackToTheStatusField) {
  RunData run = ramp_run(10, 100);
  auto m = compute_metrics(run, {});
  EXPECT_FALSE(m.commands_rejected);
  run.statuses.push_back({kT0, "bridge", 1, 0, 9, {{"ticks", 10}, {"control.rejected_out_of_range", 4}}});
  m = compute_metrics(run, {});
  EXPECT_EQ(*m.commands_rejected, 9);  // no command reject counter: the 'rejected' field
  run.statuses.push_back({kT0 + 10, "bridge", 1, 0, 9, {{"cmd.rejected_non_finite", 2}, {"rejected_future", 1}}});
  m = compute_metrics(run, {});
  EXPECT_EQ(*m.commands_rejected, 3);
  EXPECT_EQ(m.commands_rejected_counters.size(), 2u);
}

TEST(ComputeMetrics, LoggerGapsPreferTheExactCounterName) {
  RunData run = ramp_run(10, 100);
  run.samples.erase(run.samples.begin() + 4, run.samples.begin() + 6);  // seq 4, 5 missing
  auto m = compute_metrics(run, {});
  EXPECT_EQ(*m.logger_gaps, 1);
  EXPECT_EQ(m.missing_samples, 2);
  run.statuses.push_back({kT0, "logger", 1, 0, 0, {{"gap_samples", 40}, {"sensor_gaps", 3}}});
  m = compute_metrics(run, {});
  EXPECT_EQ(*m.logger_gaps, 3);
  run.statuses.push_back({kT0, "logger", 1, 0, 0, {{"gaps", 6}, {"sensor_gaps", 3}}});
  m = compute_metrics(run, {});
  EXPECT_EQ(*m.logger_gaps, 6);
}

TEST(ComputeMetrics, ParamsBeforeTheRangeAreTheInitialSet) {
  RunData run = ramp_run(50'000, 100);  // 5 s
  run.params.push_back({kT0 - 1, 1, 1e-7, 0, 1, 0, true});
  run.params.push_back({kT0 + 1'000'000, 2, 2e-7, 0, 1, 0, true});
  run.params.push_back({kT0 + 2'000'000, 3, 3e-7, 0, 1, 0, false});
  run.params.push_back({kT0 + 3'000'000, 4, 4e-7, 0, 1, 0, true});
  ReportOptions o;
  o.from_s = 1.5;
  o.to_s = 2.5;
  auto m = compute_metrics(run, o);
  EXPECT_EQ(m.params_initial->version, 2);
  EXPECT_EQ(m.params_final->version, 2);
  EXPECT_EQ(m.params_updates, 0u);
  ASSERT_EQ(m.params_history.size(), 1u);
  EXPECT_FALSE(m.params_history[0].valid);
  m = compute_metrics(run, {});
  EXPECT_EQ(m.params_initial->version, 1);
  EXPECT_EQ(m.params_final->version, 4);
  EXPECT_EQ(m.params_updates, 2u);
  EXPECT_EQ(m.samples, 50'000u);
  EXPECT_NEAR(m.duration_s, 4.9999, 1e-9);
}
