#include "reident/job_slot.hpp"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <utility>

namespace hystloop {

JobSlot::JobSlot(Job job, bool start_thread, int worker_nice) : job_(std::move(job)) {
  if (start_thread) thread_ = std::thread([this, worker_nice] { thread_main(worker_nice); });
}

JobSlot::~JobSlot() {
  if (!thread_.joinable()) return;
  wait_until_not_submitted();
  state_.store(kStop, std::memory_order_release);
  state_.notify_all();
  thread_.join();
}

bool JobSlot::submit() noexcept {
  if (!idle()) return false;
  state_.store(kSubmitted, std::memory_order_release);  // publishes the owner's job data to the worker
  state_.notify_all();
  return true;
}

bool JobSlot::release() noexcept {
  std::uint32_t expected = kDone;
  return state_.compare_exchange_strong(expected, kIdle, std::memory_order_acq_rel);
}

bool JobSlot::run_pending() {
  if (state_.load(std::memory_order_acquire) != kSubmitted) return false;
  run_job();
  return true;
}

void JobSlot::wait_until_not_submitted() const noexcept {
  while (state_.load(std::memory_order_acquire) == kSubmitted) state_.wait(kSubmitted, std::memory_order_acquire);
}

void JobSlot::thread_main(int worker_nice) {
  // Best effort: Linux applies nice per thread (tid).
  (void)::setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), worker_nice);
  for (;;) {
    std::uint32_t s = state_.load(std::memory_order_acquire);
    while (s == kIdle || s == kDone) {
      state_.wait(s, std::memory_order_acquire);
      s = state_.load(std::memory_order_acquire);
    }
    if (s == kStop) return;
    run_job();
  }
}

void JobSlot::run_job() noexcept {
  try {
    job_();
  } catch (...) {  // nothing may escape a thread; the owner's job reports its own failures
  }
  state_.store(kDone, std::memory_order_release);  // publishes the job's result to the owner
  state_.notify_all();
}

}  // namespace hystloop
