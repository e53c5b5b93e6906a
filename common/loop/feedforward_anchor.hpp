#pragma once
// Where the feedforward's model stands relative to the stage: an offset of its output and of its
// input, re-measured after each parameter swap and ramped in without a step in the voltage (the
// compensator's "swap that repairs", docs/TRACKING.md).
//
// The inverse is driven with y_model = y_ref - y_offset and its voltage u_model is sent as
// u_model + u_offset: the model believes the stage follows y = H(u - u_offset) + y_offset. After
// a swap at tick R the plan is already up to horizon_ticks past R when the samples of R arrive;
// the anchor records (u_model, y_model) for the ticks of its window from R as they are planned,
// and when their samples have all been observed sets
//
//   y_offset = mean(y_measured - y_model),   u_offset = mean(u_applied - u_model)
//
// over them (the sensor noise averaged down by sqrt(window)). The window is a whole period of the
// reference: from R, a reversal, to the second reversal after it (at least measure_ticks, at most
// max_measure_ticks). An error that is no offset averages out over a period: a loop too narrow
// errs one way on the rising branch and the other on the falling one, and a stage's transient
// after the corner is gone again. Measured over the first ticks after R alone (as on a reference
// slower than max_measure_ticks a period, where the first measure_ticks are taken), that local
// error is read as an offset and kept for the rest of the line: behind a stage with a lightly
// damped mode, a swap of the very set in use made a 10 Hz triangle 1.8 nm -> 4.3 nm.
// Feedforward only, the bridge applies what was planned and u_offset stays; with the servo,
// u_applied - u_model is what the servo adds, which the feedforward takes over (the servo's
// integrator unwinds meanwhile). The offsets move to their new values linearly from the first
// tick not yet planned: y_offset over at least min_ramp_ticks, and longer if the voltage would
// otherwise move more than max_du_per_tick per tick on its account (|dy_offset| / the model's
// slope, the secant over the branch's planned ticks); u_offset no faster than
// max_u_offset_per_tick, the rate at which the servo's integrator can hand its share over without
// a visible error.
//
// Per-sample calls are noexcept and allocation free (the window is allocated at construction).
// Constant offsets are exact for every model here: shifting u and y shifts every branch alike
// (MEM's branching points, PI's plays, Katalenic's operator), so they carry over the next
// reversals unchanged.

#include <cstdint>
#include <vector>

namespace hystloop {

class FeedforwardAnchor {
 public:
  FeedforwardAnchor(std::int64_t measure_ticks, std::int64_t max_measure_ticks, std::int64_t min_ramp_ticks,
                    double max_du_per_tick, double max_u_offset_per_tick);

  double y_offset(std::int64_t k) const noexcept;  // in effect at planned tick k [m]
  double u_offset(std::int64_t k) const noexcept;  // [V]
  double y_target() const noexcept { return y_.to; }
  double u_target() const noexcept { return u_.to; }
  bool measuring() const noexcept { return measuring_; }

  // Sets the offsets at once (a new start of the inverse) and drops a measurement under way.
  void reset(double y_offset = 0.0, double u_offset = 0.0) noexcept;
  // A swap at tick first_tick: measure the offset over the ticks from there.
  void start_measuring(std::int64_t first_tick) noexcept;
  // Moves the offsets to these values from ramp_start on, as a completed measurement does.
  void ramp_to(double y_target, double u_target, std::int64_t ramp_start, double fallback_slope) noexcept;
  // Planned tick k: the model's output y_model [m] at its voltage u_model [V]; reversal: the
  // reference turns at k.
  void planned(std::int64_t k, double y_model, double u_model, bool reversal) noexcept;
  // An observed sample. Returns true when it completed a measurement and a ramp was started at
  // ramp_start (the first tick not yet planned). fallback_slope [m/V]: when the planned voltage
  // has not moved enough for a secant.
  bool observe(std::int64_t seq, double y_measured, double u_applied, std::int64_t ramp_start,
               double fallback_slope) noexcept;

 private:
  std::int64_t measure_ticks_, max_measure_ticks_, min_ramp_ticks_;
  double max_du_per_tick_, max_u_offset_per_tick_;
  struct Ramp {
    double from = 0.0, to = 0.0;
    std::int64_t start = 0, ticks = 1;
    double at(std::int64_t k) const noexcept;
  };

  // [max_measure_ticks]: the model's y and u at each planned tick of the window
  std::vector<double> y_model_, u_model_;
  bool measuring_ = false;
  std::int64_t first_ = 0;  // first measured tick
  std::int64_t have_planned_ = 0;
  // y_measured - y_model and u_applied - u_model summed over the observed ticks of the window, and
  // over its first measure_ticks (the window of a reference without a period in it).
  struct Sums {
    double dy = 0.0, du = 0.0;
    std::int64_t n = 0;
    void add(double y, double u) noexcept { dy += y, du += u, ++n; }
  };
  Sums all_, first_ticks_;
  std::int64_t window_ = 0;  // the window's ticks once its end has been planned (0: not yet)
  int reversals_ = 0;        // reversals planned inside the window after its first tick
  double u_first_ = 0.0, y_first_ = 0.0, u_last_ = 0.0, y_last_ = 0.0;  // for the secant slope
  Ramp y_, u_;
};

}  // namespace hystloop
