#include "compensator/trajectory_checker.hpp"

#include <exception>
#include <utility>

namespace hystloop {

TrajectoryChecker::TrajectoryChecker() : worker_([this](const std::stop_token& stop) { run(stop); }) {}

TrajectoryChecker::~TrajectoryChecker() {
  worker_.request_stop();
  wake_.notify_all();
  // jthread joins here, after the check under way.
}

std::optional<TrajectoryChecker::Request> TrajectoryChecker::submit(Request request) {
  std::optional<Request> replaced;
  {
    const std::lock_guard lock(mutex_);
    if (waiting_) {
      replaced = std::move(waiting_);
    } else {
      pending_.fetch_add(1, std::memory_order_acq_rel);
    }
    waiting_ = std::move(request);
  }
  wake_.notify_all();
  return replaced;
}

std::optional<TrajectoryChecker::Outcome> TrajectoryChecker::poll() {
  if (!ready_.load(std::memory_order_acquire)) return std::nullopt;
  std::optional<Outcome> out;
  {
    const std::lock_guard lock(mutex_);
    out = std::move(done_);
    done_.reset();
    ready_.store(false, std::memory_order_release);
  }
  finished_.notify_all();  // the worker may wait to hand over the next outcome
  if (out) pending_.fetch_sub(1, std::memory_order_acq_rel);
  return out;
}

void TrajectoryChecker::wait_ready() {
  std::unique_lock lock(mutex_);
  finished_.wait(lock, [this] { return done_.has_value() || (!waiting_ && !running_); });
}

void TrajectoryChecker::run(const std::stop_token& stop) {
  for (;;) {
    std::optional<Request> taken;
    {
      std::unique_lock lock(mutex_);
      if (!wake_.wait(lock, stop, [this] { return waiting_.has_value(); })) return;
      taken = std::move(waiting_);
      waiting_.reset();
      running_ = true;
    }
    Request& request = *taken;
    Outcome outcome;
    try {
      outcome.verdict =
          Compensator::check_trajectory(request.snapshot, request.spec, request.start_s, request.learning_enabled);
    } catch (const std::exception& e) {
      outcome.refusal = e.what();
    }
    outcome.spec = request.spec;
    outcome.start_s = request.start_s;
    outcome.version = request.version;
    outcome.axis = request.axis;
    outcome.epoch = request.epoch;
    {
      std::unique_lock lock(mutex_);
      // One outcome at a time: the I/O thread polls at every sensor block (200 a second).
      finished_.wait(lock, stop, [this] { return !done_.has_value(); });
      if (stop.stop_requested()) return;
      done_ = std::move(outcome);
      running_ = false;
      ready_.store(true, std::memory_order_release);
    }
    finished_.notify_all();
  }
}

}  // namespace hystloop
