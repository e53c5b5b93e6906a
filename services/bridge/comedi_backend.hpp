#pragma once
// bridge.backend: comedi — a multifunction DAQ card through comedilib (NI, Measurement
// Computing, Advantech, ...): per axis of the stage (x, y, z) one analog output drives its piezo
// amplifier's input and one analog input reads its position sensor. Per tick one
// comedi_do_insnlist() carrying every axis's write (the tick's voltages: all outputs change
// together), then every axis's read (the sensors just after them), prepared before the loop:
// step_axes() only converts, clamps and counts. Units through comedilib's calibration, per
// channel: the board's softcal polynomials when its calibration file has them, else the range
// table (comedi_to_phys).
//
// Safety: the constructor writes every axis's safe voltage before returning (the bridge starts
// disarmed) and drops the amplifier enable (comedi.enable, when wired). Every later move to the
// safe voltage ramps at each actuator's safe_ramp_V_per_s: hold_safe(), the destructor, and a
// fatal signal (SIGSEGV, SIGABRT, ...) or std::terminate before the process dies (emergency_safe():
// prepared lists, async-signal-safe); the enable drops once the outputs are there. A read that
// fails or saturates sets SENSOR_FAULT on its axis and keeps that axis's last good position;
// comedi.fault_limit of them in a row on one axis ask the bridge to go safe
// (StageReading::go_safe). See services/bridge/README.md.

#include <comedilib.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "bridge/comedi_config.hpp"
#include "bridge/stage_backend.hpp"
#include "loop/bridge_core.hpp"

namespace hystloop {

// One direction of one channel/range: counts <-> volts.
class ComediConverter {
 public:
  // The softcal polynomial for (subdevice, channel, range) from `calibration` when it has one
  // (and the subdevice is soft-calibrated), else the range table. Throws std::runtime_error.
  ComediConverter(comedi_t* device, unsigned subdevice, unsigned channel, unsigned range,
                  const comedi_calibration_t* calibration);
  ComediConverter() = default;

  double to_V(lsampl_t counts) const noexcept;   // NaN at the range table's ends (0, maxdata)
  lsampl_t from_V(double volts) const noexcept;  // `volts` within [min_V, max_V]
  double min_V() const noexcept { return range_.min; }
  double max_V() const noexcept { return range_.max; }
  lsampl_t maxdata() const noexcept { return maxdata_; }
  bool softcal() const noexcept { return softcal_; }
  std::string describe() const;

 private:
  comedi_range range_{};  // a copy of comedi_get_range()'s
  lsampl_t maxdata_ = 0;
  bool softcal_ = false;
  comedi_polynomial_t to_phys_{};
  comedi_polynomial_t from_phys_{};
};

// Opened device (comedi_close on destruction) and its calibration file, if any.
struct ComediHandle {
  comedi_t* device = nullptr;
  comedi_calibration_t* calibration = nullptr;
  std::string calibration_path;  // empty: none found (or comedi.calibration: none)

  // Throws std::runtime_error when the device does not open, ConfigError (from `source`) when a
  // calibration file named in comedi.calibration does not parse.
  ComediHandle(const std::string& path, const std::string& calibration_setting, const std::string& source);
  ~ComediHandle();
  ComediHandle(const ComediHandle&) = delete;
  ComediHandle& operator=(const ComediHandle&) = delete;
};

// Totals over the axes under the one-axis names (what HX_STATUS has always carried), and the
// faults of each axis (reported per axis when there are several).
struct ComediCounters {
  std::atomic<std::uint64_t> transfers{0};      // comedi_do_insnlist calls of a tick
  std::atomic<std::uint64_t> write_errors{0};   // writes that did not happen (an axis each)
  std::atomic<std::uint64_t> read_errors{0};    // reads that did not happen (an axis each)
  std::atomic<std::uint64_t> saturated{0};      // reads of 0 or maxdata (or NaN): a sensor is out of range
  std::atomic<std::uint64_t> sensor_faults{0};  // readings flagged SENSOR_FAULT (read error or saturated), every axis
  std::atomic<std::uint64_t> fault_safe{0};     // times comedi.fault_limit faults in a row asked for the safe state
  std::atomic<std::uint64_t> dac_clamped{0};    // card voltages clamped to a DAC's range (0 when the config is right)
  std::atomic<std::uint64_t> safe_writes{0};    // start, hold_safe and emergency lists of the safe voltages
  std::atomic<std::uint64_t> safe_ramps{0};     // moves to the safe voltages that had to ramp (not there already)
  std::atomic<std::uint64_t> enable_rises{0};   // times the amplifier enable went active
  std::atomic<std::uint64_t> enable_drops{0};   // ... and inactive again (the safe state, a stop, an exit)
  std::array<std::atomic<std::uint64_t>, kMaxAxes> axis_sensor_faults{};  // sensor_faults, axis by axis
  std::array<std::atomic<std::uint64_t>, kMaxAxes> axis_fault_safe{};     // fault_safe, by the axis that asked
};

class ComediBackend final : public StageBackend {
 public:
  // Opens comedi.device, checks the config against the card (ConfigError naming the key; every
  // output found usable is written its safe voltage first), prepares the converters and the
  // per-tick instruction list, and writes every axis's safe voltage. `limits` has an entry per
  // axis, settings.axes of them (ParameterError otherwise).
  ComediBackend(const ComediSettings& settings, std::span<const ActuatorLimits> limits);
  // One axis (settings.axes 1): the probe's and the benchmark's.
  ComediBackend(const ComediSettings& settings, const ActuatorLimits& limits)
      : ComediBackend(settings, std::span<const ActuatorLimits>(&limits, 1)) {}
  ~ComediBackend() override;  // ramps every output to its safe voltage, drops the enable, closes the device
  ComediBackend(const ComediBackend&) = delete;
  ComediBackend& operator=(const ComediBackend&) = delete;

  // Axis x; the other axes hold what they were last given (their safe voltages at first).
  StageReading step(double u_V, double t_s, double dt_s) noexcept override;
  int axes() const noexcept override { return axes_; }
  void step_axes(std::span<const double> u_V, double t_s, double dt_s, std::span<StageReading> out) noexcept override;
  const std::string& name() const noexcept override { return name_; }
  // Ramps every axis to its safe code (an axis without an entry in `safe_u_V` gets its actuator's
  // safe_u_V) at its actuator's safe_ramp_V_per_s, one list per kRampTick_s, then writes the safe
  // list: every safe code and the enable inactive. Blocks for the ramp (none when already there).
  void hold_safe(std::span<const double> safe_u_V) noexcept override;
  void set_output_enabled(bool on) noexcept override { enable_ = on; }
  void append_counters(std::vector<std::pair<std::string, std::uint64_t>>& entries) const override;

  // The DAC code for `u_V` at axis `axis`'s piezo: clamped to its actuator's range, divided by its
  // amplifier's gain, clamped to its DAC's range, converted (counts a DAC clamp).
  lsampl_t dac_code(int axis, double u_V) noexcept;
  lsampl_t dac_code(double u_V) noexcept { return dac_code(0, u_V); }
  // Axis `axis`'s position for an ADC code (NaN when saturated).
  double position_m(int axis, lsampl_t counts) const noexcept;
  double position_m(lsampl_t counts) const noexcept { return position_m(0, counts); }
  const ComediConverter& dac(int axis = 0) const noexcept { return axis_[static_cast<std::size_t>(axis)].dac; }
  const ComediConverter& adc(int axis = 0) const noexcept { return axis_[static_cast<std::size_t>(axis)].adc; }
  const ComediCounters& counters() const noexcept { return counters_; }
  const std::string& calibration_path() const noexcept { return handle_.calibration_path; }
  // The card's line, then one per axis (the start-up log, --probe-hardware).
  std::vector<std::string> describe() const;

  // Async-signal-safe: ramps every axis from the code it was last written to its last safe code
  // and drops the enable, as hold_safe() (the fatal-signal and terminate handlers call it for the
  // live backend). True when the card took the safe list.
  bool emergency_safe() noexcept;
  // The enable line's level last written (true: active); false without an enable line.
  bool enable_active() const noexcept { return enable_active_.load(std::memory_order_relaxed); }
  // The period of the ramps to the safe voltage outside the bridge's clock [s].
  static constexpr double kRampTick_s = 1e-4;

 private:
  struct Axis {
    ComediAxisSettings settings;
    ActuatorLimits limits;
    unsigned ao_subdevice = 0;
    unsigned ai_subdevice = 0;
    ComediConverter dac;
    ComediConverter adc;
    double y_last_m = 0.0;  // the last good position (what a faulted read reports)
    int consecutive_faults = 0;
  };

  void check_against_card();  // throws ConfigError
  // Finds and configures the enable line (after the outputs: a refusal writes them safe first).
  void prepare_enable();  // throws ConfigError
  // Prepares the safe list for the axes whose output is usable (`usable`), in axis order.
  void prepare_safe_list(const std::array<bool, kMaxAxes>& usable) noexcept;
  // Writes the safe codes of the axes in the safe list: each axis's actuator's safe_u_V, or
  // `safe_u_V[i]` where given.
  void write_safe(std::span<const double> safe_u_V) noexcept;
  // safe_data_ of the axes in the safe list: `safe_u_V[i]`, or the actuator's safe_u_V.
  void set_safe_codes(std::span<const double> safe_u_V) noexcept;
  // From the codes last written to safe_data_ (ramped), then the safe list. Async-signal-safe.
  bool ramp_to_safe() noexcept;
  lsampl_t enable_level(bool active) const noexcept { return active != settings_.enable.active_low ? 1 : 0; }
  // The enable line's word at time t_s: the level, or a heartbeat's half period, while `active`.
  lsampl_t enable_at(bool active, double t_s) const noexcept;

  ComediSettings settings_;
  int axes_ = 1;
  std::string name_ = "comedi";
  ComediHandle handle_;
  std::array<Axis, kMaxAxes> axis_{};
  // The per-tick list (every axis's write, then every axis's read) and the safe list (every
  // usable axis's write), with their data words: the instructions point into these arrays.
  std::array<lsampl_t, kMaxAxes> dac_words_{};
  std::array<lsampl_t, kMaxAxes> adc_words_{};
  std::array<lsampl_t, kMaxAxes> safe_data_{};  // the safe codes (written by the constructor and hold_safe)
  std::array<bool, kMaxAxes> safe_axes_{};      // the axes in the safe list (all of them once constructed)
  // The per-tick list: every axis's write, the enable's (when wired), every axis's read.
  std::array<comedi_insn, std::size_t{2} * kMaxAxes + 1> tick_insns_{};
  std::size_t reads_at_ = 0;  // the first read's place in it
  // The safe list: every usable axis's safe code, then the enable inactive (when wired).
  std::array<comedi_insn, kMaxAxes + 1> safe_insns_{};
  comedi_insnlist tick_list_{};
  comedi_insnlist safe_list_{};
  // The ramps' list: the safe list's outputs, with their codes on the way (ramp_data_), and the
  // enable as it was (a heartbeat keeps beating until the outputs are safe).
  std::array<lsampl_t, kMaxAxes> ramp_data_{};
  lsampl_t ramp_enable_word_ = 0;
  std::array<comedi_insn, kMaxAxes + 1> ramp_insns_{};
  comedi_insnlist ramp_list_{};
  std::array<lsampl_t, kMaxAxes> ramp_step_{};  // DAC counts per kRampTick_s at the safe ramp rate (>= 1)
  // What each output was last written (the ramps start there; read by the fatal-signal handler).
  std::array<std::atomic<lsampl_t>, kMaxAxes> last_code_{};
  // The amplifier enable: what the bridge asks (real-time thread), the word the tick list writes,
  // the word the safe list writes (inactive), and the level last written.
  bool enable_ = false;
  unsigned enable_subdevice_ = 0;
  lsampl_t enable_word_ = 0;
  lsampl_t enable_idle_word_ = 0;
  std::atomic<bool> enable_active_{false};
  std::array<double, kMaxAxes> u_held_V_{};  // what step() holds the axes other than x at
  ComediCounters counters_;
};

}  // namespace hystloop
