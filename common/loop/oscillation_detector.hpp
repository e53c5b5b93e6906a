#pragma once
// A servo that oscillates: an unstable or marginal loop (gains too high for the stage, a
// resonance the notch misses, a tick of delay more than the gains were set for) rings at a
// frequency above the tracking band and grows until the actuator clamps. Tracking leaves the
// servo's output small there (the feedforward does the work; what the servo corrects is nanometres
// of error), so its output's RMS above `above_hz` beyond `rms_V` for `hold_s` is an oscillation:
// the bridge takes the stage to the safe state and names the frequency.
//
// Per tick: a second-order Butterworth high-pass at above_hz (notch_filter.hpp), its square
// averaged over kWindow_s (first order), compared with rms_V^2; the ticks in a row beyond and the
// high-passed signal's sign changes among them give the hold and the frequency (crossings / 2 /
// time). observe() allocates, locks and throws nothing.

#include <cstdint>

#include "loop/notch_filter.hpp"

namespace hystloop {

struct OscillationLimit {
  // RMS of the servo's output above above_hz [V] beyond which it oscillates; 0: no detector. The
  // servo's output at 1 nm of error is about kp x 1 nm / nominal gain (0.008 V for the deployed
  // gains): 1 V is over 100 nm of error above the tracking band, a loop ringing, not tracking. Not
  // higher: the slew limit bounds an oscillation at half the tick rate (5 V a tick: the servo's
  // output swings about +-2.5 kp V), and it must still be found.
  double rms_V = 1.0;
  double above_hz = 300.0;                    // the high-pass corner: above the tracking band [Hz]
  double hold_s = 0.02;                       // beyond the bound this long in a row [s]
  static constexpr double kWindow_s = 0.005;  // the mean square's time constant
  // Throws ParameterError naming the key ("bridge.oscillation_rms_V", ...): rms_V >= 0, above_hz in
  // [10, 0.45 rate_hz], hold_s in [2 kWindow_s, 1].
  void validate(double rate_hz) const;
  bool enabled() const noexcept { return rms_V > 0.0; }
};

class OscillationDetector {
 public:
  OscillationDetector() = default;                                              // off
  OscillationDetector(const OscillationLimit& limit, double rate_hz) noexcept;  // validated by the caller

  // One tick's servo output [V]: true on the tick the oscillation has lasted hold_s (once, until
  // reset()). NaN is taken as 0.
  bool observe(double u_V) noexcept;
  void reset() noexcept;

  // Of the oscillation found: its frequency [Hz] and its RMS when found [V] (0 before).
  double frequency_hz() const noexcept { return frequency_hz_; }
  double tripped_rms_V() const noexcept { return tripped_rms_V_; }

 private:
  NotchFilter highpass_;
  double alpha_ = 0.0, threshold2_ = 0.0, dt_s_ = 0.0;
  std::int64_t hold_ticks_ = 0;
  double mean_square_ = 0.0;
  std::int64_t beyond_ = 0, crossings_ = 0;
  bool last_positive_ = false, tripped_ = false;
  double frequency_hz_ = 0.0, tripped_rms_V_ = 0.0;
};

}  // namespace hystloop
