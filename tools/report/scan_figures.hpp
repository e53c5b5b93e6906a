#pragma once
// The scan table: a log of line-rate references (deploy/hystloop scan), each run with learning
// off and then on, cut into segments and measured. No I/O here (scan_log.hpp reads the events,
// scan_output.hpp writes the results), so each figure can be checked on generated data.
//
// Segments: every trajectory on HX_TRAJECTORY and every SET_LEARNING, SET_MODE (not the
// re-identifier's pin-model), START_EXPERIMENT, DISARM or SHUTDOWN request on HX_CONTROL ends the
// segment before it. A segment belongs to the periodic reference the compensator took last (a
// refused trajectory leaves the previous one running; a mode request, an experiment, a DISARM or
// SHUTDOWN ends the reference: a new trajectory starts the next one) and to the learning state of the last
// SET_LEARNING (off or on; a reset starts a new segment in the same state, as the compensator
// keeps it). Before any SET_LEARNING the state is the compensator's learning_active at the
// segment's end. Of several segments of one reference and learning state
// the longest analysed one is kept (e.g. the reset after an "on" starts the one measured).
//
// Per segment, on the sensor ticks received within it (e = y_ref - y, as the bridge recorded
// them, ticks with a reference):
//   rms, max |e|       after the settling time: blend_s + settle_s after a trajectory, settle_s
//                      after a learning request (the approach, and the learner's fade and lag);
//   rms_last           over the segment's last last_s seconds;
//   rms_true, max_true as rms and max, against the true position of a simulated stage
//                      (HX_SIM_TRUTH), when the log has it for every analysed tick;
//   clamped ticks      flags SATURATED | SLEW_LIMITED over the whole segment (approach included),
//                      with late (LATE_COMMAND) and safe (SAFE_STATE) ticks the same way;
//   period RMS         of each complete period from the segment's start (period = round(1 / (f dt))
//                      ticks by tick number; a period with fewer than 90 % of its ticks is left out);
//   periods to converge  the number of periods before the first one from which every period's
//                      RMS stays within converge_factor x the median of the last converge_tail
//                      periods; none when that tail is shorter than converge_tail periods (not
//                      settled) or there are fewer than converge_tail periods.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "run_data.hpp"
#include "scan_log.hpp"

namespace hystloop::report {

struct ScanOptions {
  double settle_s = 0.5;           // skipped at a segment's start (after a trajectory's blend_s too) [s]
  double last_s = 1.0;             // the "last second" window [s]
  double min_analysed_s = 0.5;     // shorter analysed segments are left out [s]
  double converge_factor = 1.2;    // periods to converge: within this factor ...
  std::size_t converge_tail = 10;  // ... of the median of this many last periods
  // Throws ParameterError naming the option ("--scan-settle", ...).
  void validate() const;
};

enum class LearningState : std::uint8_t { kUnknown, kOff, kOn };
const char* to_string(LearningState state) noexcept;

struct SegmentFigures {
  LearningState learning = LearningState::kUnknown;
  double start_s = 0.0, end_s = 0.0;  // report time axis (report_metrics.hpp)
  double analysed_from_s = 0.0;
  std::size_t ticks = 0;           // sensor ticks in the segment
  std::size_t analysed_ticks = 0;  // after the settling time, with a reference
  std::optional<double> rms_m, max_abs_m, rms_last_m;
  // rms and max |y_ref - y_true| over the same ticks, against the simulated stage's true position
  // (HX_SIM_TRUTH): only when every analysed tick has one (true_ticks == analysed_ticks).
  std::size_t true_ticks = 0;
  std::optional<double> rms_true_m, max_abs_true_m;
  std::size_t clamped_ticks = 0, saturated_ticks = 0, slew_limited_ticks = 0, late_ticks = 0, safe_ticks = 0;
  std::int64_t period_ticks = 0;
  std::vector<double> period_rms_m;
  std::optional<std::size_t> periods_to_converge;
  std::optional<double> tail_median_m;  // median RMS of the last converge_tail periods
  // The compensator's last report in the segment: its learner's RMS over the last period it
  // learned from, the periods learned, the feedforward mode; model switches and parameter swaps
  // (a new set of the model in use, e.g. the re-identifier's refit) during the segment, from its
  // counters (reported once a second: a swap in the segment's last second may be missed).
  std::optional<double> learned_rms_m;
  std::optional<std::int64_t> learning_periods;
  std::string mode;
  std::int64_t model_switches = 0;
  std::int64_t params_swaps = 0;
  double analysed_s() const noexcept { return end_s - analysed_from_s; }
};

enum class Verdict : std::uint8_t { kAccepted, kShaped, kRefused, kUnconfirmed };
const char* to_string(Verdict verdict) noexcept;

struct ReferenceFigures {
  ScanTrajectory trajectory;
  double sent_s = 0.0;
  Verdict verdict = Verdict::kUnconfirmed;
  std::string verdict_detail;  // why refused, how shaped, or the compensator's note (e.g. the corner)
  std::optional<SegmentFigures> off, on;
  std::string label() const;  // "triangle 1 µm 10 Hz"
};

struct ScanResult {
  std::vector<ReferenceFigures> references;  // periodic trajectories, in the order sent
  std::optional<double> dt_s;
  ScanOptions options;
  std::size_t refused() const noexcept;
};

ScanResult compute_scan(const RunData& run, const ScanEvents& events, const ScanOptions& options);

// The periodic trajectories the log holds: 2 or more make it a scan (hystloop-report writes the
// scan table then without --scan).
std::size_t periodic_trajectories(const ScanEvents& events) noexcept;

// Definition above; rms in any unit.
std::optional<std::size_t> periods_to_converge(const std::vector<double>& rms, double factor, std::size_t tail);

// The median of the last `tail` values (all when fewer); nullopt when empty.
std::optional<double> median_of_last(const std::vector<double>& values, std::size_t tail);

}  // namespace hystloop::report
