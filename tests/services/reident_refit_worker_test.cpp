// RefitWorker: the lock-free handoff of one refit job between the I/O thread and the worker,
// stepped by hand (no thread) and with the real thread; the owner's side never allocates.
#include "reident/refit_worker.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>

#include "core/errors.hpp"

#include "services/reident_test_data.hpp"
#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

using testdata::gain_scaled;

struct Fixture {
  MemParams truth = testdata::piezo_truth();
  MemParams in_use = gain_scaled(truth, 1.0 / 1.1);
  OnlineMemOptions options = testdata::small_reident_options(in_use).estimator;
  OnlineMemEstimator estimator{options, in_use};

  Fixture() {
    const auto rec = testdata::sine_record(truth, 3);
    for (std::size_t k = 0; k < rec.u.size(); ++k) estimator.feed(rec.u[k], rec.y[k]);
  }
};

TEST(RefitWorker, HandsOneJobOverAndBackWithoutAThread) {
  Fixture f;
  RefitWorker worker(f.options, f.estimator.make_window(), /*start_thread=*/false);
  EXPECT_FALSE(worker.threaded());
  EXPECT_TRUE(worker.idle());
  EXPECT_FALSE(worker.run_pending());  // nothing submitted
  EXPECT_FALSE(worker.release());      // nothing done

  f.estimator.snapshot(worker.job_window());
  ASSERT_TRUE(worker.submit(f.in_use, 7));
  EXPECT_FALSE(worker.idle());
  EXPECT_FALSE(worker.done());
  EXPECT_FALSE(worker.submit(f.in_use, 8));  // one job in flight

  ASSERT_TRUE(worker.run_pending());
  ASSERT_TRUE(worker.done());
  const RefitResult& r = worker.result();
  EXPECT_EQ(r.outcome.judged_against_version, 7u);
  EXPECT_EQ(r.window_samples, f.options.window_samples);
  EXPECT_EQ(r.window_first_seq, f.estimator.samples_fed() - f.options.window_samples);
  EXPECT_GT(r.duration_s, 0.0);
  ASSERT_TRUE(r.outcome.accepted) << r.outcome.reason;
  EXPECT_LT(testdata::rel_err(r.outcome.candidate.c1, f.truth.c1), 0.01);

  EXPECT_FALSE(worker.submit(f.in_use, 9));  // the result is not taken yet
  EXPECT_TRUE(worker.release());
  EXPECT_TRUE(worker.idle());
  EXPECT_FALSE(worker.release());
}

TEST(RefitWorker, TheThreadEvaluatesAndTellsTheCallback) {
  Fixture f;
  int told = 0;
  bool accepted = false;
  RefitWorker worker(f.options, f.estimator.make_window(), /*start_thread=*/true, [&](const RefitResult& r) {
    ++told;  // on the worker thread, before done() turns true
    accepted = r.outcome.accepted;
  });
  ASSERT_TRUE(worker.threaded());
  for (int round = 0; round < 3; ++round) {
    f.estimator.snapshot(worker.job_window());
    ASSERT_TRUE(worker.submit(f.in_use, 1));
    worker.wait_until_not_submitted();
    ASSERT_TRUE(worker.done());
    EXPECT_EQ(told, round + 1);
    EXPECT_TRUE(accepted) << worker.result().outcome.reason;
    EXPECT_TRUE(worker.release());
  }
}

TEST(RefitWorker, StopsWhileAJobIsInFlight) {
  Fixture f;
  std::atomic<int> told{0};
  auto worker = std::make_unique<RefitWorker>(f.options, f.estimator.make_window(), true,
                                              [&](const RefitResult&) { told.fetch_add(1); });
  f.estimator.snapshot(worker->job_window());
  ASSERT_TRUE(worker->submit(f.in_use, 1));
  const auto t0 = std::chrono::steady_clock::now();
  worker.reset();  // waits for the (time-bounded) evaluate, then joins
  const double stop_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // The job in flight was finished, not dropped and not run twice...
  EXPECT_EQ(told.load(), 1);
  // ... within the fit's time bound (max_solver_time_s plus the search: well under a second on
  // an idle machine; 10 s so that only a hang or an unbounded fit fails on a loaded one).
  EXPECT_LT(stop_s, 10.0);
}

TEST(RefitWorker, OwnerSideAllocatesNothing) {
  Fixture f;
  RefitWorker worker(f.options, f.estimator.make_window(), false);
  // Warm up once (the result's strings get their capacity on the worker side).
  f.estimator.snapshot(worker.job_window());
  worker.submit(f.in_use, 1);
  worker.run_pending();
  worker.release();
  testing::AllocationCounter counter;
  f.estimator.snapshot(worker.job_window());
  const bool submitted = worker.submit(f.in_use, 2);
  const std::size_t owner_allocations = counter.allocations();
  worker.run_pending();  // the worker's side may allocate (fit); not counted above
  testing::AllocationCounter counter2;
  const bool done = worker.done();
  const bool released = worker.release();
  EXPECT_TRUE(submitted && done && released);
  EXPECT_EQ(owner_allocations, 0u);
  EXPECT_EQ(counter2.allocations(), 0u);
}

TEST(RefitWorker, RefusesInvalidOptions) {
  OnlineMemOptions bad;
  bad.window_samples = 4;
  EXPECT_THROW(RefitWorker(bad, MemWindow{}, false), ParameterError);
}

}  // namespace
}  // namespace hystloop
