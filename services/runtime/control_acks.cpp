#include "runtime/control_acks.hpp"

#include <utility>

#include "runtime/status_reporter.hpp"

namespace hystloop {

void ControlAcks::acted(std::int64_t request_id) noexcept {
  acted_ = request_id;
  due_ = true;
}

void ControlAcks::refused(std::int64_t request_id, std::string why, std::int64_t now_us) {
  refused_ = request_id;
  why_ = std::move(why);
  refused_us_ = now_us;
  due_ = true;
}

void ControlAcks::report(StatusReporter& status) {
  status.counter("control_acted_request", static_cast<std::uint64_t>(acted_));
  status.counter("control_refused_request", static_cast<std::uint64_t>(refused_));
  due_ = false;
}

std::string ControlAcks::refusal_note(std::int64_t now_us) const {
  if (refused_ == 0 || now_us - refused_us_ > kReasonShownUs) return {};
  return "request " + std::to_string(refused_) + " refused: " + why_;
}

}  // namespace hystloop
