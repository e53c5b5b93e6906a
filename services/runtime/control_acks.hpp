#pragma once
// What a process did with the last control requests addressed to it, reported on HX_STATUS so
// that a sender can wait for its answer instead of hoping: the id of the last request it acted on
// (`control_acted_request`) and of the last it refused (`control_refused_request`), and, for a
// while after a refusal, why (in the status detail). A process reports at once after it answers
// (`due()`), not at its next period, so a waiting sender hears within milliseconds.

#include <cstdint>
#include <string>

namespace hystloop {

class StatusReporter;

class ControlAcks {
 public:
  // How long the reason of a refusal stays in the status detail [us].
  static constexpr std::int64_t kReasonShownUs = 10'000'000;

  void acted(std::int64_t request_id) noexcept;
  void refused(std::int64_t request_id, std::string why, std::int64_t now_us);

  // A request was answered since the last report: report now.
  bool due() const noexcept { return due_; }

  // Adds control_acted_request and control_refused_request (0 until there is one) and clears due().
  void report(StatusReporter& status);

  // "request <id> refused: <why>" while the refusal is recent, else empty.
  std::string refusal_note(std::int64_t now_us) const;

  std::int64_t last_acted() const noexcept { return acted_; }
  std::int64_t last_refused() const noexcept { return refused_; }

 private:
  std::int64_t acted_ = 0;
  std::int64_t refused_ = 0;
  std::string why_;
  std::int64_t refused_us_ = 0;
  bool due_ = false;
};

}  // namespace hystloop
