#include "bridge/comedi_config.hpp"

#include <cmath>

#include <spdlog/fmt/fmt.h>

namespace hystloop {
namespace {

constexpr const char* kArefs[] = {"ground", "common", "diff", "other"};

ComediChannelSettings load_channel(const Config& config, const std::string& prefix, const char* default_aref) {
  ComediChannelSettings c;
  c.subdevice = static_cast<int>(config.get_int_in_range(prefix + "subdevice", c.subdevice, -1, 255));
  c.channel = static_cast<int>(config.get_int_in_range(prefix + "channel", c.channel, 0, 65535));
  c.range = static_cast<int>(config.get_int_in_range(prefix + "range", c.range, 0, 255));
  const std::string aref = config.get<std::string>(prefix + "aref", default_aref);
  c.aref = -1;
  for (int i = 0; i < 4; ++i) {
    if (aref == kArefs[i]) c.aref = i;
  }
  if (c.aref < 0) config.fail(prefix + "aref", "must be ground, common, diff or other (got '" + aref + "')");
  return c;
}

}  // namespace

const std::vector<std::string>& comedi_config_keys() {
  static const std::vector<std::string> keys = {"comedi.device",
                                                "comedi.ao.subdevice",
                                                "comedi.ao.channel",
                                                "comedi.ao.range",
                                                "comedi.ao.aref",
                                                "comedi.ai.subdevice",
                                                "comedi.ai.channel",
                                                "comedi.ai.range",
                                                "comedi.ai.aref",
                                                "comedi.amplifier_gain_V_per_V",
                                                "comedi.sensor.scale_m_per_V",
                                                "comedi.sensor.offset_m",
                                                "comedi.fault_limit",
                                                "comedi.calibration"};
  return keys;
}

const char* aref_name(int aref) noexcept { return aref >= 0 && aref < 4 ? kArefs[aref] : "?"; }

ComediSettings load_comedi_settings(const Config& config) {
  ComediSettings s;
  s.source = config.source();
  s.device = config.get<std::string>("comedi.device", s.device);
  if (s.device.empty()) config.fail("comedi.device", "must name the card's device file, e.g. /dev/comedi0");
  s.ao = load_channel(config, "comedi.ao.", "ground");
  s.ai = load_channel(config, "comedi.ai.", "ground");
  s.amplifier_gain_V_per_V = config.get_in_range("comedi.amplifier_gain_V_per_V", s.amplifier_gain_V_per_V, 1e-3, 1e4);
  s.sensor_scale_m_per_V = config.get_in_range("comedi.sensor.scale_m_per_V", s.sensor_scale_m_per_V, -1.0, 1.0);
  if (s.sensor_scale_m_per_V == 0.0 || !std::isfinite(s.sensor_scale_m_per_V)) {
    config.fail("comedi.sensor.scale_m_per_V", "must not be 0 (the sign says the wiring's: see --probe-hardware)");
  }
  s.sensor_offset_m = config.get_in_range("comedi.sensor.offset_m", s.sensor_offset_m, -1.0, 1.0);
  s.fault_limit = static_cast<int>(config.get_int_in_range("comedi.fault_limit", s.fault_limit, 1, 100000));
  s.calibration = config.get<std::string>("comedi.calibration", s.calibration);
  if (s.calibration.empty()) config.fail("comedi.calibration", "must be auto, none or a calibration file's path");
  return s;
}

std::string describe(const ComediSettings& s) {
  const auto channel = [](const ComediChannelSettings& c) {
    return fmt::format("subdevice {} channel {} range {} aref {}",
                       c.subdevice < 0 ? std::string("auto") : std::to_string(c.subdevice), c.channel, c.range,
                       aref_name(c.aref));
  };
  return fmt::format(
      "comedi: {}, ao {} (x{} V/V to the piezo), ai {} ({:+.6g} m/V, offset {:.6g} m), go safe after {} "
      "faulted reads in a row, calibration {}",
      s.device, channel(s.ao), s.amplifier_gain_V_per_V, channel(s.ai), s.sensor_scale_m_per_V, s.sensor_offset_m,
      s.fault_limit, s.calibration);
}

}  // namespace hystloop
