#pragma once
// The re-identifier's counters, by name, as HX_STATUS reports them. Every sample that is not
// fed and every refit that is not published is counted under its reason. They only count up;
// RESET_COUNTERS is the service's CounterSet (services/runtime/counter_set.hpp), as everywhere.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "ident/fit_status.hpp"

namespace hystloop {

enum class ReidentCounter : std::uint8_t {
  samples_fed,           // handed to the estimator (incl. one poison marker per refused block)
  skipped_safe_state,    // flagged SAFE_STATE: the bridge is ramping/holding, not following commands
  skipped_sensor_fault,  // flagged SENSOR_FAULT: y is the last good value
  seq_gaps,              // a jump forward in seq not explained by samples refused on the wire
  samples_missed,        // ticks missing in those gaps
  seq_restarts,          // seq went backwards or repeated a tick (a bridge restart)
  non_finite,            // NaN/Inf samples (a marker per block refused on the wire, or fed): poison the window
  dropouts,              // y stuck while u moves: poisons the window
  refits_attempted,
  refits_accepted,
  refits_superseded,         // judged against a set replaced meanwhile (HX_PARAMS), or of a window a new
                             // reference has made another's: not adopted
  refits_implausible,        // accepted by the fit, but its gain leaves the rig's band: not published
                             // (also counted in refits_rejected_out_of_range)
  refits_held,               // accepted while the operator holds the set in use: reported, not published
  params_adopted,            // sets from HX_PARAMS that became the set in use
  params_echo,               // our own sets coming back
  params_stale,              // valid sets not newer than the set in use
  params_invalid,            // valid = false sets
  params_implausible,        // valid sets whose gain leaves the rig's band (models/gain_plausibility.hpp)
  command_versions_dropped,  // HX_COMMAND version changes beyond VersionTimeline's capacity (pending at once)
  sensor_blocks_wrong_axes,  // HX_SENSOR blocks without the re-identifier's axis: not fitted, as refused
  params_other_axis,         // HX_PARAMS sets for another axis: another re-identifier's, ignored
  window_restarts,           // a new reference requested (HX_TRAJECTORY, HX_SCAN): the window starts again
  refits_rejected_first      // + (FitStatus - kFirstRefusal) for each refusal reason a refit can have
};

// A refit's refusals start at size_mismatch: `ok` is no refusal, so it has no counter.
inline constexpr FitStatus kFirstRefusal = FitStatus::size_mismatch;
inline constexpr std::size_t kRefusalCount =
    static_cast<std::size_t>(FitStatus::poisoned_window) - static_cast<std::size_t>(kFirstRefusal) + 1;
inline constexpr std::size_t kReidentCounterCount =
    static_cast<std::size_t>(ReidentCounter::refits_rejected_first) + kRefusalCount;

// "samples_fed", ..., "refits_rejected_<fit status>" (index by counter).
std::string_view counter_name(std::size_t index) noexcept;

class ReidentCounters {
 public:
  void add(ReidentCounter c, std::uint64_t n = 1) noexcept { values_[index(c)] += n; }
  // ok (a caller's bug, not a refit's outcome) counts as solver_failure.
  void add_rejected(FitStatus s) noexcept { values_[rejected_index(s)] += 1; }
  void set(ReidentCounter c, std::uint64_t total) noexcept { values_[index(c)] = total; }  // mirrored totals
  // Since start.
  std::uint64_t get(ReidentCounter c) const noexcept { return at(index(c)); }
  std::uint64_t rejected(FitStatus s) const noexcept { return at(rejected_index(s)); }
  std::uint64_t rejected_total() const noexcept;
  std::uint64_t at(std::size_t i) const noexcept { return values_[i]; }

  static constexpr std::size_t index(ReidentCounter c) noexcept { return static_cast<std::size_t>(c); }
  static constexpr std::size_t rejected_index(FitStatus s) noexcept {
    if (static_cast<int>(s) < static_cast<int>(kFirstRefusal)) s = FitStatus::solver_failure;
    return index(ReidentCounter::refits_rejected_first) + static_cast<std::size_t>(s) -
           static_cast<std::size_t>(kFirstRefusal);
  }

 private:
  std::array<std::uint64_t, kReidentCounterCount> values_{};
};

}  // namespace hystloop
