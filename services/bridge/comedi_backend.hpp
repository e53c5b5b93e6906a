#pragma once
// bridge.backend: comedi — a multifunction DAQ card through comedilib (NI, Measurement
// Computing, Advantech, ...): one analog output drives the piezo amplifier's input, one analog
// input reads the position sensor. Per tick one comedi_do_insnlist() carrying a write (the
// tick's voltage) and a read (the sensor just after it), both prepared before the loop: step()
// only converts, clamps and counts. Units through comedilib's calibration: the board's softcal
// polynomials when its calibration file has them, else the range table (comedi_to_phys).
//
// Safety: the constructor writes the safe voltage before returning (the bridge starts disarmed);
// hold_safe() and the destructor step the output to it; a fatal signal (SIGSEGV, SIGABRT, ...)
// or std::terminate steps it there too before the process dies (emergency_safe()). A read that
// fails or saturates sets SENSOR_FAULT and keeps the last good position; comedi.fault_limit of
// them in a row ask the bridge to go safe (StageReading::go_safe). See services/bridge/README.md.

#include <comedilib.h>

#include <atomic>
#include <cstdint>
#include <string>

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

struct ComediCounters {
  std::atomic<std::uint64_t> transfers{0};      // comedi_do_insnlist calls of step()
  std::atomic<std::uint64_t> write_errors{0};   // the write did not happen (rc < 1)
  std::atomic<std::uint64_t> read_errors{0};    // the read did not happen (rc < 2)
  std::atomic<std::uint64_t> saturated{0};      // read 0 or maxdata (or NaN): the sensor is out of range
  std::atomic<std::uint64_t> sensor_faults{0};  // ticks flagged SENSOR_FAULT (read error or saturated)
  std::atomic<std::uint64_t> fault_safe{0};     // times comedi.fault_limit faults in a row asked for the safe state
  std::atomic<std::uint64_t> dac_clamped{0};    // card voltage clamped to the DAC's range (0 when the config is right)
  std::atomic<std::uint64_t> safe_writes{0};    // hold_safe / start / emergency writes of the safe voltage
};

class ComediBackend final : public StageBackend {
 public:
  // Opens comedi.device, checks the config against the card (ConfigError naming the field;
  // when the output channel is usable the safe voltage is written first), prepares the
  // converters and the per-tick instruction list, and writes the safe voltage.
  ComediBackend(const ComediSettings& settings, const ActuatorLimits& limits);
  ~ComediBackend() override;  // steps to the safe voltage, then closes the device
  ComediBackend(const ComediBackend&) = delete;
  ComediBackend& operator=(const ComediBackend&) = delete;

  StageReading step(double u_V, double t_s, double dt_s) noexcept override;
  const std::string& name() const noexcept override { return name_; }
  void hold_safe(std::span<const double> safe_u_V) noexcept override;
  void append_counters(std::vector<std::pair<std::string, std::uint64_t>>& entries) const override;

  // The DAC code for `u_V` at the piezo: clamped to the actuator's range, divided by the
  // amplifier's gain, clamped to the DAC's range, converted (counts a DAC clamp).
  lsampl_t dac_code(double u_V) noexcept;
  // The position for an ADC code (NaN when saturated).
  double position_m(lsampl_t counts) const noexcept;
  const ComediConverter& dac() const noexcept { return dac_; }
  const ComediConverter& adc() const noexcept { return adc_; }
  const ComediCounters& counters() const noexcept { return counters_; }
  const std::string& calibration_path() const noexcept { return handle_.calibration_path; }
  std::string describe() const;

  // Async-signal-safe: writes the last safe code with one comedi_do_insnlist (the fatal-signal
  // and terminate handlers call it for the live backend). True when the card took it.
  bool emergency_safe() noexcept;

 private:
  void check_against_card();  // throws ConfigError
  void write_safe(double safe_u_V) noexcept;

  ComediSettings settings_;
  ActuatorLimits limits_;
  std::string name_ = "comedi";
  ComediHandle handle_;
  unsigned ao_subdevice_ = 0;
  unsigned ai_subdevice_ = 0;
  ComediConverter dac_;
  ComediConverter adc_;
  // The per-tick list (write, read) and the safe list (write), with their data words.
  lsampl_t dac_word_ = 0;
  lsampl_t adc_word_ = 0;
  comedi_insn tick_insns_[2]{};
  comedi_insn safe_insn_{};
  lsampl_t safe_data_ = 0;  // the safe code (written by the constructor and hold_safe)
  comedi_insnlist tick_list_{};
  comedi_insnlist safe_list_{};
  double y_last_m_ = 0.0;
  int consecutive_faults_ = 0;
  ComediCounters counters_;
};

}  // namespace hystloop
