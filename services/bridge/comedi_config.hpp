#pragma once
// The comedi backend's configuration (bridge.backend: comedi): the card's device file and, per
// axis of the stage, the analog output that drives its amplifier's input, the analog input that
// reads its position sensor, the amplifier's gain and the sensor's scale and offset. Axis x's are
// the `comedi.ao.*`, `comedi.ai.*`, `comedi.amplifier_gain_V_per_V`, `comedi.sensor.*` keys (a
// one-axis config is a complete one); axes y and z have the same keys under `comedi.y.*` and
// `comedi.z.*`, each defaulting to axis x's except the channels, which must be given (two axes on
// one channel would drive one amplifier twice). Read and validated here (ConfigError naming the
// key); what can only be checked against the card (subdevice types, channel and range counts, the
// DAC range covering the actuator's range) is checked by ComediBackend when it opens the device,
// with the same kind of message.

#include <array>
#include <string>
#include <vector>

#include "core/config.hpp"
#include "models/axis_coupling.hpp"

namespace hystloop {

struct ComediChannelSettings {
  int subdevice = -1;  // -1: the card's first analog output (ao) / analog input (ai) subdevice
  int channel = 0;
  int range = 0;  // index into the subdevice's range table (see --probe-hardware)
  int aref = 0;   // AREF_GROUND 0, AREF_COMMON 1, AREF_DIFF 2, AREF_OTHER 3 (ground | common | diff | other)
};

// The amplifier enable: one digital output the bridge holds active only while it runs and is not
// in the safe state (armed, or ramping down to the safe voltage), for the amplifier's enable input
// or an external watchdog relay in its enable chain. `level`: the line is the state; `heartbeat`:
// while active the line toggles at heartbeat_hz (a relay that drops without edges also drops
// when the process is killed, hangs or loses power: `level` leaves the line where it was then).
// Every exit path drops it (docs/TIMING.md, "Amplifier enable").
struct ComediEnableSettings {
  int subdevice = -1;         // -1: the card's first digital I/O (or digital output) subdevice
  int channel = -1;           // -1: no enable line (the amplifier is enabled by hand)
  bool heartbeat = false;     // false: level
  double heartbeat_hz = 500;  // the square wave's frequency while active [Hz], below bridge.rate_hz / 2
  bool active_low = false;    // the line is low while active (level), and idles high
  bool configured() const noexcept { return channel >= 0; }
};

// One axis's channel pair and scales.
struct ComediAxisSettings {
  ComediChannelSettings ao{};            // -> the amplifier's input
  ComediChannelSettings ai{};            // <- the position sensor's output
  double amplifier_gain_V_per_V = 25.0;  // V at the piezo per V at the card's output
  double sensor_scale_m_per_V = 1e-6;    // m of position per V at the card's input (sign = wiring)
  double sensor_offset_m = 0.0;          // position at 0 V on the input [m]

  // The voltage at the card for `u_V` at the piezo, and back.
  double card_V(double u_V) const noexcept { return u_V / amplifier_gain_V_per_V; }
  double position_m(double sensor_V) const noexcept { return sensor_offset_m + sensor_scale_m_per_V * sensor_V; }
};

// The card's settings, with axis x's channel pair as its own members (comedi.ao.* ...: what a
// one-axis config and the code written for it use) and the other axes' in `other_axes`; axis(i)
// gives any axis's.
struct ComediSettings : ComediAxisSettings {
  std::string source = "<defaults>";  // the config's file name, for messages found at open
  std::string device = "/dev/comedi0";
  int fault_limit = 10;              // this many faulted reads in a row on one axis -> the bridge goes safe
  std::string calibration = "auto";  // auto (comedilib's default file when the board has one) | none | a path
  ComediEnableSettings enable{};     // comedi.enable.*: the amplifier enable line (none by default)
  int axes = 1;                      // axes driven (bridge.axes): x, then y, then z
  std::array<ComediAxisSettings, kMaxAxes - 1> other_axes{};  // y, z (comedi.y.*, comedi.z.*)

  // Axis i's (0 <= i < kMaxAxes): x is this struct's own.
  const ComediAxisSettings& axis(int i) const noexcept {
    return i == 0 ? *this : other_axes[static_cast<std::size_t>(i - 1)];
  }
  ComediAxisSettings& axis(int i) noexcept { return i == 0 ? *this : other_axes[static_cast<std::size_t>(i - 1)]; }
};

// Every comedi.* key, those of axes y and z included (added to bridge_config_keys()).
const std::vector<std::string>& comedi_config_keys();

// Reads and validates the comedi.* keys for a stage of `axes` axes (bridge.axes); throws
// ConfigError naming the key. Axis x's keys and every key given are validated whatever the
// backend (one config serves the simulators and the card); `required` (bridge.backend comedi)
// makes the channels of axes y and z mandatory. Keys of an axis beyond `axes` are refused.
// `rate_hz` (bridge.rate_hz) bounds comedi.enable.heartbeat_hz (two ticks per period at least).
ComediSettings load_comedi_settings(const Config& config, int axes, bool required, double rate_hz);

// "ground", "common", "diff", "other" for 0..3.
const char* aref_name(int aref) noexcept;

// For the start-up log: the card's line, then one per axis.
std::vector<std::string> describe(const ComediSettings& settings);

}  // namespace hystloop
