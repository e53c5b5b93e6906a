#include "reident/refit_worker.hpp"

#include <exception>
#include <string>
#include <utility>

#include "core/clock.hpp"

namespace hystloop {

RefitWorker::RefitWorker(const OnlineMemOptions& options, MemWindow window, bool start_thread, OnEvaluated on_evaluated,
                         std::optional<GainPlausibility> plausibility)
    : options_(options),
      window_(std::move(window)),
      on_evaluated_(std::move(on_evaluated)),
      plausibility_(plausibility),
      slot_([this] { evaluate_job(); }, start_thread) {
  options_.validate();
  if (plausibility_) plausibility_->validate();
}

bool RefitWorker::submit(const MemParams& in_use, std::uint64_t version) noexcept {
  if (!idle()) return false;
  in_use_ = in_use;
  in_use_version_ = version;
  return slot_.submit();  // publishes window_, in_use_ to the worker
}

void RefitWorker::evaluate_job() {
  const double start_s = monotonic_s();
  try {
    result_.outcome = OnlineMemEstimator::evaluate(window_, in_use_, in_use_version_, options_);
  } catch (const std::exception& e) {  // nothing may escape a thread; a failed refit is a refusal
    result_.outcome = MemRefitOutcome{};
    result_.outcome.judged_against_version = in_use_version_;
    result_.outcome.reason = std::string("evaluate threw: ") + e.what();
  }
  result_.implausible = false;
  if (plausibility_ && result_.outcome.accepted) {
    ModelParamSet candidate;
    candidate.mem = result_.outcome.candidate;
    try {
      require_plausible(candidate, *plausibility_);
    } catch (const std::exception& e) {
      result_.outcome.accepted = false;
      result_.outcome.status = FitStatus::out_of_range;
      result_.outcome.reason = std::string("the fit is not this stage's: ") + e.what();
      result_.implausible = true;
    }
  }
  result_.duration_s = monotonic_s() - start_s;
  result_.window_first_seq = window_.first_seq;
  result_.window_samples = window_.u.size();
  if (on_evaluated_) {
    try {
      on_evaluated_(result_);
    } catch (...) {  // a reporting failure must not lose the result
    }
  }
}

}  // namespace hystloop
