#pragma once
// One job at a time handed between an owner thread (the re-identifier's I/O thread) and a worker
// thread, without locks: what RefitWorker (the MEM refit) and ModelChooser (the model choice)
// both use. The slot's state is one atomic:
//
//   idle --submit() (owner)--> submitted --job ran (worker)--> done --release() (owner)--> idle
//
// Whoever moves the state away from a value owns the job's data in that state (the owner fills
// it while idle and reads the result while done; the worker reads and writes it while
// submitted), so no datum is touched by both threads at once. No owner-side call blocks,
// allocates or locks (submit's wake-up is one futex call). The worker thread runs at
// `worker_nice`: a fit never competes on equal terms with the I/O thread.
// Without a thread (start_thread = false) nothing runs by itself: run_pending() runs a submitted
// job on the calling thread, so a test drives the same handoff step by step.

#include <atomic>
#include <cstdint>
#include <functional>
#include <thread>

namespace hystloop {

class JobSlot {
 public:
  // Runs on the worker (or in run_pending); must not throw (what escapes is swallowed, and the
  // job still ends as done).
  using Job = std::function<void()>;

  JobSlot(Job job, bool start_thread, int worker_nice = 10);
  ~JobSlot();  // waits for a job in flight (the jobs' own time budgets bound it), stops, joins
  JobSlot(const JobSlot&) = delete;
  JobSlot& operator=(const JobSlot&) = delete;

  bool idle() const noexcept { return state_.load(std::memory_order_acquire) == kIdle; }
  bool done() const noexcept { return state_.load(std::memory_order_acquire) == kDone; }
  // Owner: hands the job's data over. False (and nothing happens) unless idle().
  bool submit() noexcept;
  // Owner: a done slot back to idle. False if it was not done.
  bool release() noexcept;
  // No thread: runs a submitted job here. True if it ran one.
  bool run_pending();
  // Blocks until no job is in flight (tests and shutdown; never on the I/O thread).
  void wait_until_not_submitted() const noexcept;
  bool threaded() const noexcept { return thread_.joinable(); }

 private:
  static constexpr std::uint32_t kIdle = 0, kSubmitted = 1, kDone = 2, kStop = 3;
  void thread_main(int worker_nice);
  void run_job() noexcept;

  Job job_;
  std::atomic<std::uint32_t> state_{kIdle};
  std::thread thread_;
};

}  // namespace hystloop
