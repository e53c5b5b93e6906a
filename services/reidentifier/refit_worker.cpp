#include "reidentifier/refit_worker.hpp"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <chrono>
#include <exception>
#include <string>
#include <utility>

namespace hystloop {

RefitWorker::RefitWorker(const OnlineMemOptions& options, MemWindow window, bool start_thread,
                         OnEvaluated on_evaluated)
    : options_(options), window_(std::move(window)), on_evaluated_(std::move(on_evaluated)) {
  options_.validate();
  if (start_thread) thread_ = std::thread([this] { thread_main(); });
}

RefitWorker::~RefitWorker() {
  if (!thread_.joinable()) return;
  wait_until_not_submitted();
  state_.store(kStop, std::memory_order_release);
  state_.notify_all();
  thread_.join();
}

bool RefitWorker::submit(const MemParams& in_use, std::uint64_t version) noexcept {
  if (!idle()) return false;
  in_use_ = in_use;
  in_use_version_ = version;
  state_.store(kSubmitted, std::memory_order_release);  // publishes window_, in_use_ to the worker
  state_.notify_one();
  return true;
}

bool RefitWorker::release() noexcept {
  std::uint32_t expected = kDone;
  return state_.compare_exchange_strong(expected, kIdle, std::memory_order_acq_rel);
}

bool RefitWorker::run_pending() {
  if (state_.load(std::memory_order_acquire) != kSubmitted) return false;
  evaluate_job();
  return true;
}

void RefitWorker::wait_until_not_submitted() const noexcept {
  while (state_.load(std::memory_order_acquire) == kSubmitted) state_.wait(kSubmitted, std::memory_order_acquire);
}

void RefitWorker::thread_main() {
  // Best effort: a fit (tens of ms of CPU) yields to the I/O thread and the rig's loop
  // processes sharing the cores. Linux applies nice per thread (tid).
  (void)::setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), kWorkerNice);
  for (;;) {
    std::uint32_t s = state_.load(std::memory_order_acquire);
    while (s == kIdle || s == kDone) {
      state_.wait(s, std::memory_order_acquire);
      s = state_.load(std::memory_order_acquire);
    }
    if (s == kStop) return;
    evaluate_job();
  }
}

void RefitWorker::evaluate_job() {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  try {
    result_.outcome = OnlineMemEstimator::evaluate(window_, in_use_, in_use_version_, options_);
  } catch (const std::exception& e) {  // nothing may escape a thread; a failed refit is a refusal
    result_.outcome = MemRefitOutcome{};
    result_.outcome.judged_against_version = in_use_version_;
    result_.outcome.reason = std::string("evaluate threw: ") + e.what();
  }
  result_.duration_s = std::chrono::duration<double>(clock::now() - start).count();
  result_.window_first_seq = window_.first_seq;
  result_.window_samples = window_.u.size();
  if (on_evaluated_) {
    try {
      on_evaluated_(result_);
    } catch (...) {  // a reporting failure must not lose the result
    }
  }
  state_.store(kDone, std::memory_order_release);  // publishes result_ to the owner
  state_.notify_all();
}

}  // namespace hystloop
