#include "bridge/comedi_config.hpp"

#include <cmath>

#include <spdlog/fmt/fmt.h>

namespace hystloop {
namespace {

constexpr const char* kArefs[] = {"ground", "common", "diff", "other"};

// An axis's own keys, after "comedi." (axis x's) or "comedi.y." ...
constexpr const char* kAxisFields[] = {"ao.subdevice",           "ao.channel",           "ao.range",       "ao.aref",
                                       "ai.subdevice",           "ai.channel",           "ai.range",       "ai.aref",
                                       "amplifier_gain_V_per_V", "sensor.scale_m_per_V", "sensor.offset_m"};

// "comedi.<field>" for x, "comedi.y.<field>" for y ...
std::string axis_key(int axis, const std::string& field) { return axis_field("comedi." + field, axis); }

ComediChannelSettings load_channel(const Config& config, const std::string& prefix, ComediChannelSettings c) {
  c.subdevice = static_cast<int>(config.get_int_in_range(prefix + "subdevice", c.subdevice, -1, 255));
  c.channel = static_cast<int>(config.get_int_in_range(prefix + "channel", c.channel, 0, 65535));
  c.range = static_cast<int>(config.get_int_in_range(prefix + "range", c.range, 0, 255));
  const std::string aref = config.get<std::string>(prefix + "aref", aref_name(c.aref));
  c.aref = -1;
  for (int i = 0; i < 4; ++i) {
    if (aref == kArefs[i]) c.aref = i;
  }
  if (c.aref < 0) config.fail(prefix + "aref", "must be ground, common, diff or other (got '" + aref + "')");
  return c;
}

// Axis `axis`'s keys, each one absent taken from `a` (axis x's for y and z, the defaults for x).
ComediAxisSettings load_axis(const Config& config, int axis, ComediAxisSettings a) {
  a.ao = load_channel(config, axis_key(axis, "ao."), a.ao);
  a.ai = load_channel(config, axis_key(axis, "ai."), a.ai);
  a.amplifier_gain_V_per_V =
      config.get_in_range(axis_key(axis, "amplifier_gain_V_per_V"), a.amplifier_gain_V_per_V, 1e-3, 1e4);
  const std::string scale = axis_key(axis, "sensor.scale_m_per_V");
  a.sensor_scale_m_per_V = config.get_in_range(scale, a.sensor_scale_m_per_V, -1.0, 1.0);
  if (a.sensor_scale_m_per_V == 0.0 || !std::isfinite(a.sensor_scale_m_per_V)) {
    config.fail(scale, "must not be 0 (the sign says the wiring's: see --probe-hardware)");
  }
  a.sensor_offset_m = config.get_in_range(axis_key(axis, "sensor.offset_m"), a.sensor_offset_m, -1.0, 1.0);
  return a;
}

std::string subdevice_text(int subdevice) { return subdevice < 0 ? std::string("auto") : std::to_string(subdevice); }

}  // namespace

const std::vector<std::string>& comedi_config_keys() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> k = {"comedi.device"};
    for (const char* field : kAxisFields) k.push_back(axis_key(0, field));
    k.insert(k.end(), {"comedi.fault_limit", "comedi.calibration", "comedi.enable.subdevice", "comedi.enable.channel",
                       "comedi.enable.mode", "comedi.enable.heartbeat_hz", "comedi.enable.active"});
    for (int axis = 1; axis < kMaxAxes; ++axis) {
      for (const char* field : kAxisFields) k.push_back(axis_key(axis, field));
    }
    return k;
  }();
  return keys;
}

const char* aref_name(int aref) noexcept { return aref >= 0 && aref < 4 ? kArefs[aref] : "?"; }

ComediEnableSettings load_enable(const Config& config, double rate_hz) {
  ComediEnableSettings e;
  e.subdevice = static_cast<int>(config.get_int_in_range("comedi.enable.subdevice", e.subdevice, -1, 255));
  e.channel = static_cast<int>(config.get_int_in_range("comedi.enable.channel", e.channel, -1, 65535));
  const std::string mode = config.get<std::string>("comedi.enable.mode", "level");
  if (mode != "level" && mode != "heartbeat") {
    config.fail("comedi.enable.mode", "must be level or heartbeat (got '" + mode + "')");
  }
  e.heartbeat = mode == "heartbeat";
  e.heartbeat_hz = config.get_in_range("comedi.enable.heartbeat_hz", e.heartbeat_hz, 1.0, rate_hz / 2.0);
  const std::string active = config.get<std::string>("comedi.enable.active", "high");
  if (active != "high" && active != "low") {
    config.fail("comedi.enable.active", "must be high or low (got '" + active + "')");
  }
  e.active_low = active == "low";
  return e;
}

ComediSettings load_comedi_settings(const Config& config, int axes, bool required, double rate_hz) {
  ComediSettings s;
  s.source = config.source();
  s.axes = axes;
  s.device = config.get<std::string>("comedi.device", s.device);
  if (s.device.empty()) config.fail("comedi.device", "must name the card's device file, e.g. /dev/comedi0");
  static_cast<ComediAxisSettings&>(s) = load_axis(config, 0, s);
  s.fault_limit = static_cast<int>(config.get_int_in_range("comedi.fault_limit", s.fault_limit, 1, 100000));
  s.calibration = config.get<std::string>("comedi.calibration", s.calibration);
  if (s.calibration.empty()) config.fail("comedi.calibration", "must be auto, none or a calibration file's path");
  s.enable = load_enable(config, rate_hz);

  // Which axes' channels are known: x's always (defaults or keys), y's and z's when given. Only
  // those are compared; the card's backend needs them all (`required`).
  std::array<bool, kMaxAxes> ao_known{true}, ai_known{true};
  for (int axis = 1; axis < kMaxAxes; ++axis) {
    const std::string section = "comedi." + std::string(axis_name(axis));
    if (axis >= axes) {
      if (config.has(section)) {
        config.fail(section, fmt::format("the stage has {} ax{} (bridge.axes): there is no axis {}", axes,
                                         axes == 1 ? "is" : "es", axis_name(axis)));
      }
      continue;
    }
    const auto at = static_cast<std::size_t>(axis);
    ao_known[at] = config.has(axis_key(axis, "ao.channel"));
    ai_known[at] = config.has(axis_key(axis, "ai.channel"));
    if (required && !ao_known[at]) {
      config.fail(axis_key(axis, "ao.channel"),
                  fmt::format("must be given for axis {} (bridge.backend comedi, bridge.axes {}): the output to its "
                              "amplifier has no default, as two axes on one channel would drive one amplifier twice",
                              axis_name(axis), axes));
    }
    if (required && !ai_known[at]) {
      config.fail(axis_key(axis, "ai.channel"),
                  fmt::format("must be given for axis {} (bridge.backend comedi, bridge.axes {}): the input from its "
                              "sensor has no default, as two axes on one channel would read one sensor twice",
                              axis_name(axis), axes));
    }
    s.axis(axis) = load_axis(config, axis, s);
  }

  // Two axes on one (subdevice, channel): refused on the later axis's channel key. Subdevice -1
  // (the card's first of its kind) is one subdevice; -1 against a number is checked at open.
  for (int j = 1; j < axes; ++j) {
    for (int i = 0; i < j; ++i) {
      const auto ii = static_cast<std::size_t>(i), jj = static_cast<std::size_t>(j);
      const ComediAxisSettings& a = s.axis(i);
      const ComediAxisSettings& b = s.axis(j);
      if (ao_known[ii] && ao_known[jj] && a.ao.subdevice == b.ao.subdevice && a.ao.channel == b.ao.channel) {
        config.fail(axis_key(j, "ao.channel"),
                    fmt::format("axis {} drives ao subdevice {} channel {} already: two axes on one output would "
                                "drive one amplifier twice",
                                axis_name(i), subdevice_text(a.ao.subdevice), a.ao.channel));
      }
      if (ai_known[ii] && ai_known[jj] && a.ai.subdevice == b.ai.subdevice && a.ai.channel == b.ai.channel) {
        config.fail(axis_key(j, "ai.channel"),
                    fmt::format("axis {} reads ai subdevice {} channel {} already: each axis needs its own sensor's "
                                "input",
                                axis_name(i), subdevice_text(a.ai.subdevice), a.ai.channel));
      }
    }
  }
  return s;
}

std::vector<std::string> describe(const ComediSettings& s) {
  const auto channel = [](const ComediChannelSettings& c) {
    return fmt::format("subdevice {} channel {} range {} aref {}", subdevice_text(c.subdevice), c.channel, c.range,
                       aref_name(c.aref));
  };
  std::vector<std::string> lines;
  lines.push_back(fmt::format(
      "comedi: {}, {} ax{}, one instruction list per tick, go safe after {} faulted reads in a row on an axis, "
      "calibration {}",
      s.device, s.axes, s.axes == 1 ? "is" : "es", s.fault_limit, s.calibration));
  const ComediEnableSettings& e = s.enable;
  lines.push_back(
      !e.configured()
          ? std::string("comedi: no amplifier enable line (comedi.enable.channel -1): the amplifier stays enabled "
                        "when the bridge stops or dies")
      : e.heartbeat ? fmt::format("comedi: amplifier enable on dio subdevice {} channel {}: a {} Hz heartbeat "
                                  "while armed or ramping, idle {} otherwise",
                                  subdevice_text(e.subdevice), e.channel, e.heartbeat_hz, e.active_low ? "high" : "low")
                    : fmt::format("comedi: amplifier enable on dio subdevice {} channel {}: {} while armed or "
                                  "ramping, {} otherwise",
                                  subdevice_text(e.subdevice), e.channel, e.active_low ? "low" : "high",
                                  e.active_low ? "high" : "low"));
  for (int axis = 0; axis < s.axes; ++axis) {
    const ComediAxisSettings& a = s.axis(axis);
    lines.push_back(fmt::format("comedi {}: ao {} (x{} V/V to the piezo), ai {} ({:+.6g} m/V, offset {:.6g} m)",
                                axis_name(axis), channel(a.ao), a.amplifier_gain_V_per_V, channel(a.ai),
                                a.sensor_scale_m_per_V, a.sensor_offset_m));
  }
  return lines;
}

}  // namespace hystloop
