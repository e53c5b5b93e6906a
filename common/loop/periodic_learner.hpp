#pragma once
// Iterative learning control for a periodic reference (a raster line repeated thousands of
// times). The compensator adds, per planned tick k, a correction c_k [m] to the reference r_k it
// feeds into the model's inverse; the inverse cancels the stage, so the plant from the corrected
// reference to the position is close to identity (T ≈ 1, up to model error), and what repeats
// in the error e_k = r_k - y_k can be learned from one period and removed in the next ones (y_k
// as the compensator observes it: the measured position less what the servo's voltage made, so
// that the servo, which works against every correction, is no part of T):
//
//   c_new[i] = clamp( Q( c_applied[i] + gain * e[i] ), ±max_correction_m ),  i = phase in the period
//
// (the plain update; the lag-compensated one, the default, is below). Q, the robustness filter,
// is a triangle window of 2M - 1 taps, q_j = (M - |j|) / M^2, applied
// circularly over the period (the signal is periodic, so the period's end continues into its
// start): two M-tick running means, one looking back and one looking ahead, hence O(N) per update
// whatever M. Its frequency response is the square of an M-tick mean's,
//
//   Q(f) = ( sin(pi f M dt) / (M sin(pi f dt)) )^2,   0 <= Q(f) <= 1,  Q(0) = 1,
//
// -6 dB where the mean is -3 dB (f ≈ 0.443 / (M dt)) with its first null at 1 / (M dt); M is the
// longest window whose -6 dB frequency is at or above cutoff_hz (M >= 2): at 10 kHz, 1 kHz gives
// M = 4, -6 dB at 1.14 kHz, the null at 2.5 kHz, ||q||^2 = sum q_j^2 = (2M^2 + 1) / (3M^3) = 0.172.
// It is zero-phase (symmetric taps: it delays nothing, so the learned signal stays aligned with
// the error it came from, and a period needs no phase model of the plant) and never amplifies
// (0 <= Q <= 1): in the plain update, with |1 - gain*T(f)| <= 1 where Q is not small, each update
// is a contraction (the lag-compensated one's condition is below), and Q stops the learning where
// the plant is not known well enough: |1 - gain*T| exceeds 1 once the phase of T passes
// acos(gain / 2) (76° for gain 0.5), which a delay of d ticks reaches at 2.1 kHz / d; there Q must
// be small. With the 1 kHz filter and gain 0.5, max |Q (1 - gain*T)|
// for a delay of 2, 3, 4 ticks is 0.61, 0.79, 0.94 (still learning), 1.06 for 5 (where only the
// clamp bounds the table).
//
// Why a complete period: the update is a whole-period operation (Q mixes neighbouring phases,
// across the wrap too), and a period with a hole would learn a sample that is not there; such a
// period is skipped (counted), the table in use stays. The samples arrive a horizon (~50 ms)
// after their tick was planned, so the table computed from period p is adopted at the first
// period boundary the plan reaches after p has been observed: p + 2 when the period is longer
// than the lag, later when it is shorter (200 Hz, 50 ticks, with a 520-tick lag: p + 11).
// Adopted only at a boundary, the table in use never changes mid-period.
//
// The lag: with L = D + 1 periods between a period and the adoption of the table learned from it
// (L = 2 for 1000 ticks under a 520-tick lag, 3 for 400, 4 for 200, 6 for 100, 11 for 50), the
// plain update adds to what was *applied* in period p (recorded per tick in a ring when planned),
// so c_{p+L} = Q(c_p + gain*e_p) splits into L chains, each converging as without lag but one step
// every L periods. (Adding to the table in use instead, c_{p+L} = Q(c_{p+L-1} + gain*e_p), is a
// delayed integrator, unstable at L = 11.) The lag-compensated update lets every period improve
// the next table: it predicts the error the newest table c_cur (the one waiting for a boundary,
// else the one in use) would give from the error measured under c_applied, taking T = 1,
// ê = e - (c_cur - c_applied), and learns from that:
//
//   c_new = clamp( Q( (1 - gain) c_cur + gain (c_applied + e) ) )
//
// Per harmonic, with c_p the table learned from period p, e_p = d - T c_{p-L} (d: the error
// without learning), the tables follow
//
//   c_p = Q (1 - gain) c_{p-1} + Q gain (1 - T) c_{p-L} + Q gain d,
//   characteristic polynomial  z^{D+1} - Q (1 - gain) z^D - Q gain (1 - T)      (plain: z^{D+1} - Q (1 - gain T)).
//
// Same fixed point as the plain update, E = d (1 - Q) / (1 - Q + gain Q T); with T = 1 the lag
// term vanishes and each table converges by Q (1 - gain) per *period* whatever D. Stability: on
// |z| = 1, |Q (1 - gain) z^D + Q gain (1 - T)| <= Q (1 - gain) + Q gain |1 - T|, so (Rouché) every
// root is inside the unit circle, for every D, when
//
//   Q (1 - gain + gain |1 - T|) < 1,   i.e.  |1 - T| < 1 + (1 - Q) / (gain Q)   (Q = 1: |1 - T| < 1),
//
// a gain error 0 < T < 2 or, at |T| = 1, a phase error within ±60°; as D grows it is also
// necessary. A given D allows more: D = 0 is the plain update (|1 - gain T| < 1: T < 4 for gain
// 0.5), and, for gain 0.5 and Q = 1, a real T up to 3.0, 2.56, 2.36, 2.19, 2.07 at D = 1, 2, 3,
// 5, 10, a phase at |T| = 1 up to 67°, 64°, 63°, 62°, 61°. Per-period rate (the largest root,
// gain 0.5, Q = 1) for T = 0.8 / 0.9 / 1.1 / 1.2: 0.65 / 0.59 / 0.36 / 0.32 at D = 1, 0.70 / 0.63 /
// 0.44 / 0.54 at D = 2, 0.80 / 0.73 / 0.70 / 0.77 at D = 5, 0.88 / 0.83 / 0.82 / 0.87 at D = 10
// (plain, per period: |1 - gain T|^{1/L}, 0.95 for T = 0.9 at D = 10). With the 1 kHz filter a
// plant delay of 1, 3, 4 ticks gives a largest root of 0.60, 0.89, 0.98 at D = 1 and 0.90, 0.98,
// 0.999 at D = 10; 5 ticks is outside (1.05, 1.01), as it is for the plain update (1.06). For a
// plant outside the bound (|1 - T| > 1 where Q is near 1, as a model gain off by a factor of two)
// set lag_compensated = false: the plain update asks only |Q (1 - gain T)| < 1, at the price of
// one step per L periods. (With gain 1 the two updates are the same.) What no update can avoid:
// the tables learned from the first L periods saw no correction act, so the error of period
// P < 2L is d - T c_{P-L} with c_{P-L} ≈ d, a remaining (1 - T) d (at 200 Hz under a 520-tick lag,
// period 20 still uses c_9, learned before the first table was in use).
//
// Noise: with T = 1 and white sensor noise of RMS sigma alone, e_p = -c_{p-L} - n_p, so per
// harmonic C_p = Q((1 - gain) C_{p-1} - gain N_p) (lag-compensated: the lag term is gone) or
// Q((1 - gain) C_{p-L} - gain N_p) (plain): the same stationary variance in both, the DC does not
// random-walk, and the learned signal's variance is
// sum_f Q^2 gain^2 sigma^2 / (1 - Q^2 (1 - gain)^2) / N <= gain ||q||^2 sigma^2 / (2 - gain)
// (0.24 nm RMS for sigma = 1 nm, gain 0.5, M = 4; 0.27, 0.30, 0.41 nm for gain 0.6, 0.7, 1). What
// differs is the correlation: successive lag-compensated tables correlate by Q (1 - gain); plain
// ones L periods apart do, neighbours not. With T != 1 the lag term stays and the variance is
// sigma^2 times the energy of the recursion's impulse response (0.233 nm for T = 0.9 e^{-jw},
// D = 10).
//
// A new table never steps the reference either: from the boundary where it is adopted it takes
// over from the one in use along a linear blend of blend_s (at most the period). A step in the
// correction is a step in the reference that the stage's exact inverse (models/stage_inverse.hpp)
// answers with a ringing at half the tick rate, about 2.2 times the step and decaying by |z0| =
// 0.93 per tick: on the live loop the first table of a 10 Hz line, a few nanometres at phase 0,
// rang at the slew limit for a dozen ticks (26 nm of error) until the tables settled. Blended
// over 50 ticks the same step is a kink of 1/50 of it. What was applied is what the update
// reads (c_applied per tick), so the blend changes the path to the fixed point, not the point.
//
// A line's first tables enter gradually: the correction applied is the table in use times a ramp
// rising linearly from 0 to 1 over ramp_periods periods from the line's first adoption. The first
// table cannot have seen T: it was learned from the L periods before any correction acted, which
// the lag-compensated update composes (taking T = 1) into nearly the whole learning-off error
// d, and with a wrong T, or a plant whose hysteresis answers a change of its input over several
// cycles, that whole table lands in one period. Measured on the two-mode stage (bench/tracking_table
// --scan --two-mode --wrong-models), a 100 Hz, 0.5 um sine under a model with its dominant mode
// 10 % low: learning off 1.16 nm RMS; the first table at once made periods 7 and 8 1.36 and 1.65 nm
// (1.43 times), most of it a mean offset (1.1 nm in period 8) that Coleman-Hodgdon's slowly
// relaxing branches made of a zero-mean correction, learned away over three more periods; a plain
// update's half table did almost the same (1.52). Ramped in over 4 periods the worst period is
// 1.25 nm (1.08 times), and the lines converge to the same error 0-2 periods later (the scan
// tables' periods [20, 30) are unchanged). It also gives the monitor below a period under a
// fraction of the table to see a plant the update cannot learn. The update reads what was
// applied, so the ramp changes the path to the fixed point, not the point.
//
// Stop, off, restart and reset never step the reference: the correction in use fades out
// linearly over fade_s (a step of at most max_correction_m / fade_ticks per tick on the fade's
// account, beside the table's own tick-to-tick change), then a new learning starts from zero at
// the first period boundary after the fade.
//
// A parameter swap of the hysteresis model is survived: the correction lives in metres of
// reference, not in volts, so it means the same to the new inverse as to the old one; what the
// swap changed in the error is a new repeating error, which the following periods learn away.
//
// Learning that makes things worse is stopped. The model the inverse uses may be wrong where Q is
// not small (a mode off in frequency, a delay left out, a gain far off), and then |1 - T| exceeds
// the bound above and the tables grow period after period; the clamp at max_correction_m only
// bounds the damage. So the periods a line learns from before any table acts (the L periods of the
// lag) give its learning-off error, the baseline B (their RMS pooled), and a period learned under
// a table with an error RMS above B (monitor_ratio + 4 / sqrt(n)), n the period's ticks, or two in
// a row above B (monitor_ratio + 2 / sqrt(n)), end the learning of that line: the table it falls
// back to is the corrections that were applied over its best period (when that period was better
// than the baseline), held as they are, or none (faded out). It is counted (divergences) and shown (diverged, until the
// line is restarted, reset or learning is turned on again), and it does not learn that line again. The margin and the
// second period are the sensor noise's: a period's RMS of white noise alone scatters by about 1 / sqrt(2n) of itself (7
// % at n = 100), and a divergence grows period after period while a noisy period does not repeat. A parameter set
// swapped in under a table (one the line does not hold) steps the error for a few periods while the tables learn the
// new set's error (params_swapped): the periods until a lag and five periods after the swap are not compared.
//
// Everything is allocated in the constructor; correction(), observe() and the state changes are
// noexcept and allocate, lock and log nothing.

#include <cstdint>
#include <limits>
#include <vector>

namespace hystloop {

struct LearningConfig {
  bool enabled = true;               // learn when the reference is periodic
  double gain = 0.5;                 // learning gain in (0, 1]
  double cutoff_hz = 1000.0;         // robustness filter Q: -6 dB at or just above it, in [1/max_period_s, fs/4]
  double max_correction_m = 0.2e-6;  // |c_k| bound [m]: the learned table is clamped inside it
  double max_period_s = 1.0;         // longest period learned; a longer one is not learned
  double fade_s = 0.05;              // stop/off/restart/reset: the correction fades out over this time
  double blend_s = 0.005;            // a new table takes over from the one in use over this time (0: at once)
  double ramp_periods = 4.0;  // a line's correction rises from 0 to its tables over this many periods (0: at once)
  // A line that has taken this many tables (its table under half of max_correction_m) keeps the
  // parameter set it learned under: a set for its model that arrives later waits
  // (Compensator::params_held_by_learning) until learning stops, is reset or the line ends.
  // 0: sets are swapped in as they come. 1 (from the line's first table): a swap is a step of the
  // error the tables are learning, and it costs the same before the line has converged as after,
  // while the tables correct what the new set would (a model far off, whose table nears its
  // bound, is not held).
  std::int64_t hold_params_after = 1;
  // Learn from every period through the lag (c_new = Q((1 - gain) c_cur + gain (c_applied + e)));
  // false: the plain update, one step per L periods, for a plant with |1 - T| > 1 where Q is not small.
  bool lag_compensated = true;
  // A period learned under a table with an error RMS above this many times the line's learning-off
  // error plus 4 / sqrt(n), or two in a row above it plus 2 / sqrt(n) (the noise's margins, see
  // above), stop the learning of that line; 0: never.
  double monitor_ratio = 1.05;
  // Throws ParameterError naming the field ("learning.gain", ...).
  void validate(double dt_s) const;
};

// What the learner has done, for status and tests.
struct LearnerFigures {
  std::uint64_t periods_completed = 0;  // observed to their end (learned + skipped)
  std::uint64_t periods_learned = 0;    // a new table was computed from them
  std::uint64_t periods_skipped = 0;    // a sample was missing (or NaN, or too late): not learned from
  std::uint64_t tables_adopted = 0;     // new tables taken into use (at a period boundary)
  std::uint64_t tables_this_line = 0;   // of those, since learning last (re)started
  std::uint64_t ticks_held = 0;         // planned ticks a limit held back (hold()): not learned from
  double last_error_rms_m = 0.0;        // e over the last period learned from
  double last_error_max_m = 0.0;        // max |e| over it
  double correction_rms_m = 0.0;        // of the table in use (0 when none)
  bool active = false;                  // learning a period (false: idle or fading out)
  bool fading = false;
  std::uint64_t divergences = 0;  // lines whose learning the monitor stopped
  bool diverged = false;          // the line's learning was stopped by the monitor (holding or faded)
  bool holding = false;           // ... and its best period's corrections are held (false: faded out)
  double baseline_rms_m = 0.0;    // the line's learning-off error RMS (0: not measured yet)
  double best_rms_m = 0.0;        // its best period under a table (0: none yet)
  std::int64_t period_ticks = 0;  // of the periodic reference (0: none, or refused)
};

class PeriodicLearner {
 public:
  // Validates the config (ParameterError). max_lag_ticks: how much later than planned a sample
  // may arrive (the horizon plus a sensor block); a later one counts as missing.
  PeriodicLearner(const LearningConfig& config, double dt_s, std::int64_t max_lag_ticks);

  // A periodic reference whose period is period_ticks and whose phase 0 is at tick k0: forget
  // what was learned (fading it out) and learn this one. period_ticks < 2 or longer than
  // max_period_s: idle (correction 0).
  void restart(std::int64_t k0, std::int64_t period_ticks) noexcept;
  // The reference is not periodic any more: fade out, then 0.
  void stop() noexcept;
  // Off fades out like stop (and forgets); on learns the same period again from zero.
  void set_enabled(bool on) noexcept;
  // Forget what was learned (fading it out) and learn the same period again from zero.
  void reset() noexcept;

  // The correction [m] to add to the reference r_k at planned tick k (k increases by 1 between
  // calls). Records r_k and c_k for the update. 0 before k0 and while idle.
  double correction(std::int64_t k, double r_k_m) noexcept;
  // The measured position of tick k: ticks in increasing order, at most max_lag_ticks after the
  // plan; ticks may be missing; NaN = no sample. Completing a period computes the next table,
  // adopted at the next period boundary of the plan.
  void observe(std::int64_t k, double y_m) noexcept;
  // A parameter set was swapped in at tick k: the periods up to a lag and five periods after it
  // are not compared with the baseline (the swap's step of the error, which the tables then learn).
  void params_swapped(std::int64_t k) noexcept;
  // Planned tick k (the last correction() asked for) was held back by a limit of the plan: its
  // error is not the table's to remove, and learning it would only grow the table there tick
  // after tick (the learning's windup). Its phase keeps what was applied (e taken as 0).
  void hold(std::int64_t k) noexcept;

  const LearnerFigures& figures() const noexcept { return figures_; }
  bool enabled() const noexcept { return enabled_; }
  // Q as built: the half-width M, its -6 dB frequency, first null and ||q||^2 (for a period of at
  // least M ticks; a shorter period uses M = the period: only its mean is learned).
  std::int64_t filter_half_width() const noexcept { return window_; }
  double filter_cutoff_hz() const noexcept { return filter_cutoff_hz_; }
  double filter_null_hz() const noexcept;
  double filter_norm_sq() const noexcept;
  std::int64_t fade_ticks() const noexcept { return fade_ticks_; }
  double ramp_periods() const noexcept { return ramp_periods_; }
  std::int64_t blend_ticks() const noexcept { return blend_ticks_; }
  std::int64_t max_period_ticks() const noexcept { return max_period_; }
  double gain() const noexcept { return gain_; }
  bool lag_compensated() const noexcept { return lag_compensated_; }

 private:
  // kHolding: the monitor stopped the learning and holds the best table as it is.
  enum class Mode : std::uint8_t { kIdle, kLearning, kFading, kHolding };

  void begin_again() noexcept;                        // the target changed: fade out or start at once
  void start_learning(std::int64_t from_k) noexcept;  // zero table, first period at or after from_k
  void learn_from_period() noexcept;                  // acc_ -> next_ (filter, clamp)
  void account_skipped(std::uint64_t n) noexcept;
  // A period learned with error RMS e: the baseline, the best table, or the end of the learning.
  // Returns false when the learning of the line ends here.
  bool monitor(double e_rms_m) noexcept;
  std::int64_t phase(std::int64_t k) const noexcept;             // of k in the table's period [0, n)
  double in_use(std::int64_t k, std::int64_t i) const noexcept;  // table_ at phase i, blended at tick k
  double ramp(std::int64_t k) const noexcept;                    // the line's ramp at tick k, in [0, 1]
  std::size_t slot(std::int64_t k) const noexcept;

  double dt_s_, gain_;
  double applied_weight_;  // of c_applied in acc_: 1 (plain), gain (lag-compensated)
  double max_correction_m_;
  // Derived from the config in the constructor's body.
  std::int64_t max_period_ = 0, window_ = 2, fade_ticks_ = 1, blend_ticks_ = 0;
  double filter_cutoff_hz_ = 0.0;
  bool lag_compensated_;

  // The periodic reference asked for (target) and whether learning is on.
  bool enabled_;
  bool has_target_ = false;
  std::int64_t k0_ = 0, n_ = 0;

  Mode mode_ = Mode::kIdle;
  std::int64_t table_k0_ = 0, table_n_ = 0, table_m_ = 1;  // phase basis and window of table_
  bool have_table_ = false;                                // table_ holds a learned table
  bool pending_ = false;                                   // next_ holds one waiting for a boundary
  double pending_rms_m_ = 0.0, table_rms_m_ = 0.0;         // RMS of next_ and of table_
  double scale_ = 1.0;                                     // of the table while fading
  double fade_from_ = 1.0;                                 // the ramp the fade started from
  // The ramp: from the line's first adoption (ramp_k0_) over ramp_ticks_ (0: none).
  double ramp_periods_;
  std::int64_t ramp_k0_ = 0, ramp_ticks_ = 0;
  double prev_scale_ = 1.0;     // of prev_ in the blend (the ramp prev_ was applied at when a hold began)
  std::int64_t fade_left_ = 0;  // ticks until the fade reaches 0
  // The blend from prev_ (the table in use before, zero for the first) to table_, from tick
  // adopted_k_ over blend_n_ ticks.
  bool have_prev_ = false;
  std::int64_t adopted_k_ = 0, blend_n_ = 0;
  std::int64_t learn_start_ = 0;
  std::int64_t last_planned_ = std::numeric_limits<std::int64_t>::min();

  // The period being observed.
  bool cur_open_ = false, cur_ok_ = false;
  std::int64_t cur_start_ = 0, cur_next_ = 0, expect_start_ = 0,
               last_observed_ = std::numeric_limits<std::int64_t>::min();
  double cur_sum_sq_ = 0.0, cur_max_ = 0.0;
  bool cur_under_table_ = false;  // a correction was applied in the period being observed

  // The monitor: its ratio (0: off), the line's baseline and best period, and that period's table.
  double monitor_ratio_;
  double baseline_rms_m_ = 0.0, best_rms_m_ = 0.0;
  double baseline_sum_sq_ = 0.0;  // of the learning-off periods' RMS, pooled into baseline_rms_m_
  std::int64_t baseline_periods_ = 0;
  bool baseline_closed_ = false;   // a period under a table was observed: the baseline is what it is
  bool above_once_ = false;        // the last period compared was above the limit
  std::int64_t compare_from_ = 0;  // periods starting before this tick are not compared (a swap)
  bool have_good_ = false, stopped_by_monitor_ = false;
  std::vector<double> applied_, good_;  // per phase: c_applied in the period being observed, in the best

  // Per planned tick (ring over the lag): which tick the slot holds, its r_k and applied c_k.
  std::vector<std::int64_t> ring_k_;
  std::vector<double> ring_r_, ring_c_;
  std::vector<std::uint8_t> ring_held_;  // the plan could not apply what tick asked (hold())
  // Per phase [max_period]: the table in use, the next one, the one table_ is taking over from,
  // the period being observed's share of the update (c_applied + gain*e, or gain*(c_applied +
  // e)), and the filter's scratch.
  std::vector<double> table_, next_, prev_, acc_, tmp_;
  LearnerFigures figures_;
};

}  // namespace hystloop
