#include "reident/reident_counters.hpp"

namespace hystloop {

namespace {
constexpr std::array<std::string_view, kReidentCounterCount> kNames{
    "samples_fed",
    "skipped_safe_state",
    "skipped_sensor_fault",
    "seq_gaps",
    "samples_missed",
    "seq_restarts",
    "non_finite",
    "dropouts",
    "refits_attempted",
    "refits_accepted",
    "refits_superseded",
    "refits_implausible",
    "refits_held",
    "params_adopted",
    "params_echo",
    "params_stale",
    "params_invalid",
    "params_implausible",
    "command_versions_dropped",
    "sensor_blocks_wrong_axes",
    "params_other_axis",
    "window_restarts",
    // One per refusal reason, in FitStatus's order from kFirstRefusal.
    "refits_rejected_size_mismatch",
    "refits_rejected_non_finite_data",
    "refits_rejected_constant_input",
    "refits_rejected_too_few_branches",
    "refits_rejected_too_few_samples",
    "refits_rejected_out_of_range",
    "refits_rejected_solver_failure",
    "refits_rejected_no_improvement",
    "refits_rejected_poisoned_window",
};
static_assert(!kNames.back().empty(), "a counter without a name: kNames must follow ReidentCounter");
}  // namespace

std::string_view counter_name(std::size_t index) noexcept {
  return index < kNames.size() ? kNames[index] : std::string_view("unknown");
}

std::uint64_t ReidentCounters::rejected_total() const noexcept {
  std::uint64_t n = 0;
  for (std::size_t s = 0; s < kRefusalCount; ++s) n += at(index(ReidentCounter::refits_rejected_first) + s);
  return n;
}

}  // namespace hystloop
