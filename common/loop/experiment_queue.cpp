#include "loop/experiment_queue.hpp"

#include <string>
#include <utility>

#include "core/errors.hpp"

namespace hystloop {

void ExperimentQueue::add(const ExperimentSpec& spec) {
  spec.validate();
  if (spec.multisine && !spec.samples) {
    throw ParameterError("experiment", "a multisine is designed at the loop's tick before it is queued");
  }
  if (!has_running_) {
    running_ = Running{spec};
    has_running_ = true;
    return;
  }
  if (queued_ == kCapacity) {
    throw ParameterError(
        "experiment", "queue full: " + std::to_string(kCapacity) + " experiments already wait behind the running one");
  }
  waiting_[(head_ + queued_) % kCapacity] = spec;
  ++queued_;
}

void ExperimentQueue::stop(double end_s) noexcept {
  queued_ = 0;
  if (!has_running_) return;
  if (!running_.started) {
    has_running_ = false;  // it never commanded anything
    return;
  }
  if (end_s < running_.end_s) running_.end_s = end_s;
}

ExperimentQueue::Step ExperimentQueue::step(double t_s) noexcept {
  Step out;
  if (!has_running_) return out;
  if (!running_.started) {
    running_.started = true;
    running_.start_s = t_s;
    running_.end_s = experiment_end_s(t_s, running_.spec);
  }
  while (t_s >= running_.end_s && queued_ > 0) {
    // Back to back: the next starts where this one ended, at a whole period (phase 0).
    const double start = running_.end_s;
    // Swapped, not copied: the finished spec's multisine samples then wait in the free slot and are
    // freed by the add() that reuses it, not here on the per-tick path.
    std::swap(running_.spec, waiting_[head_]);
    head_ = (head_ + 1) % kCapacity;
    --queued_;
    running_.started = true;
    running_.start_s = start;
    running_.end_s = experiment_end_s(start, running_.spec);
  }
  if (t_s < running_.end_s) {
    out.active = true;
    out.voltage_V = experiment_voltage(running_.spec, t_s - running_.start_s);
    return out;
  }
  has_running_ = false;
  out.ended = true;
  return out;
}

}  // namespace hystloop
