#pragma once
// The comedi backend's configuration (bridge.backend: comedi): the card's device file, the
// analog output that drives the amplifier's input, the analog input that reads the position
// sensor, the amplifier's gain and the sensor's scale and offset. Read from the `comedi.*`
// keys, validated there (ConfigError naming the field); what can only be checked against the
// card (subdevice types, channel and range counts, the DAC range covering the actuator's range)
// is checked by ComediBackend when it opens the device, with the same kind of message.

#include <string>
#include <vector>

#include "core/config.hpp"

namespace hystloop {

struct ComediChannelSettings {
  int subdevice = -1;  // -1: the card's first analog output (ao) / analog input (ai) subdevice
  int channel = 0;
  int range = 0;  // index into the subdevice's range table (see --probe-hardware)
  int aref = 0;   // AREF_GROUND 0, AREF_COMMON 1, AREF_DIFF 2, AREF_OTHER 3 (ground | common | diff | other)
};

struct ComediSettings {
  std::string source = "<defaults>";  // the config's file name, for messages found at open
  std::string device = "/dev/comedi0";
  ComediChannelSettings ao{};            // -> the amplifier's input
  ComediChannelSettings ai{};            // <- the position sensor's output
  double amplifier_gain_V_per_V = 25.0;  // V at the piezo per V at the card's output
  double sensor_scale_m_per_V = 1e-6;    // m of position per V at the card's input (sign = wiring)
  double sensor_offset_m = 0.0;          // position at 0 V on the input [m]
  int fault_limit = 10;                  // this many faulted reads in a row -> the bridge goes safe
  std::string calibration = "auto";      // auto (comedilib's default file when the board has one) | none | a path

  // The voltage at the card for `u_V` at the piezo, and back.
  double card_V(double u_V) const noexcept { return u_V / amplifier_gain_V_per_V; }
  double position_m(double sensor_V) const noexcept { return sensor_offset_m + sensor_scale_m_per_V * sensor_V; }
};

// Every comedi.* key (added to bridge_config_keys()).
const std::vector<std::string>& comedi_config_keys();

// Reads and validates the comedi.* keys; throws ConfigError naming the field.
ComediSettings load_comedi_settings(const Config& config);

// "ground", "common", "diff", "other" for 0..3.
const char* aref_name(int aref) noexcept;

// One line for the start-up log.
std::string describe(const ComediSettings& settings);

}  // namespace hystloop
