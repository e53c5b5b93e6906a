#include "bridge/probe_hardware.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <exception>
#include <iterator>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include <spdlog/fmt/fmt.h>

#include "bridge/comedi_backend.hpp"
#include "core/cli.hpp"

namespace hystloop {
namespace {

const char* subdevice_type_name(int type) {
  // By COMEDI_SUBD_*, from COMEDI_SUBD_UNUSED = 0.
  static constexpr const char* kNames[] = {
      "unused", "analog input", "analog output",    "digital input", "digital output", "digital I/O", "counter",
      "timer",  "memory",       "calibration DACs", "processor",     "serial",         "pwm"};
  static_assert(COMEDI_SUBD_UNUSED == 0 && static_cast<std::size_t>(COMEDI_SUBD_PWM) == std::size(kNames) - 1);
  return type >= 0 && type < static_cast<int>(std::size(kNames)) ? kNames[type] : "other";
}

std::string flag_names(int flags) {
  std::string s;
  const auto add = [&](int bit, const char* name) {
    if ((flags & bit) != 0) s += s.empty() ? name : std::string(", ") + name;
  };
  add(SDF_READABLE, "readable");
  add(SDF_WRITABLE, "writable");
  add(SDF_GROUND, "aref ground");
  add(SDF_COMMON, "aref common");
  add(SDF_DIFF, "aref diff");
  add(SDF_OTHER, "aref other");
  add(SDF_SOFT_CALIBRATED, "soft-calibrated");
  return s.empty() ? "-" : s;
}

const char* unit_name(unsigned unit) { return unit == UNIT_volt ? "V" : unit == UNIT_mA ? "mA" : ""; }

void list_card(const ComediHandle& h, std::FILE* out) {
  comedi_t* dev = h.device;
  const int n = comedi_get_n_subdevices(dev);
  std::fprintf(out, "card: driver %s, board %s, %d subdevices\n", comedi_get_driver_name(dev),
               comedi_get_board_name(dev), n);
  for (int s = 0; s < n; ++s) {
    const unsigned su = static_cast<unsigned>(s);
    const int type = comedi_get_subdevice_type(dev, su);
    const int channels = comedi_get_n_channels(dev, su);
    std::fprintf(out, "  subdevice %d: %s, %d channels, maxdata %u, flags: %s\n", s, subdevice_type_name(type),
                 channels, comedi_get_maxdata(dev, su, 0), flag_names(comedi_get_subdevice_flags(dev, su)).c_str());
    if (type != COMEDI_SUBD_AI && type != COMEDI_SUBD_AO) continue;
    for (int r = 0, nr = comedi_get_n_ranges(dev, su, 0); r < nr; ++r) {
      if (const comedi_range* range = comedi_get_range(dev, su, 0, static_cast<unsigned>(r))) {
        std::fprintf(out, "    range %d: [%g, %g] %s\n", r, range->min, range->max, unit_name(range->unit));
      }
    }
  }
  std::fprintf(out, "calibration: %s\n",
               h.calibration_path.empty() ? "none found (conversions use the range tables)"
                                          : ("softcal file " + h.calibration_path).c_str());
}

ProbeFit fit(const std::vector<double>& x, const std::vector<double>& y, int faults) {
  ProbeFit f;
  f.samples = static_cast<int>(x.size());
  f.faults = faults;
  if (x.size() < 3) return f;
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size(); ++i) mx += x[i], my += y[i];
  mx /= static_cast<double>(x.size());
  my /= static_cast<double>(x.size());
  double sxx = 0, syy = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxx += (x[i] - mx) * (x[i] - mx);
    syy += (y[i] - my) * (y[i] - my);
    sxy += (x[i] - mx) * (y[i] - my);
  }
  if (sxx <= 0) return f;
  f.gain_V_per_V = sxy / sxx;
  f.offset_V = my - f.gain_V_per_V * mx;
  f.r = syy > 0 ? sxy / std::sqrt(sxx * syy) : 0.0;
  return f;
}

// The triangle at the card: 0 -> +1 -> -1 -> 0 over phase 0..1.
double triangle(double phase) {
  if (phase < 0.25) return 4 * phase;
  if (phase < 0.75) return 2 - 4 * phase;
  return 4 * phase - 4;
}

int drive(const BridgeSettings& settings, const ProbeOptions& o, std::FILE* out) {
  const int axis = o.axis;
  const auto at = static_cast<std::size_t>(axis);
  const ComediAxisSettings& c = settings.comedi.axis(axis);
  const ActuatorLimits& a = settings.limits_of(axis);
  // Every axis's output is opened and held at its safe voltage; only `axis` moves.
  const std::array<ActuatorLimits, kMaxAxes> limits = settings.axes_limits();
  const auto n = static_cast<std::size_t>(settings.axes);
  ComediBackend backend(settings.comedi,
                        std::span<const ActuatorLimits>(limits).first(n));  // refuses what the card lacks
  for (const std::string& line : backend.describe()) std::fprintf(out, "%s\n", line.c_str());
  const double center_V = c.card_V(a.safe_u_V);
  const double lo_V = std::max({center_V - o.amplitude_V, c.card_V(a.u_min_V), backend.dac(axis).min_V()});
  const double hi_V = std::min({center_V + o.amplitude_V, c.card_V(a.u_max_V), backend.dac(axis).max_V()});
  std::fprintf(out,
               "driving%s: triangle %.4g V -> %.4g V -> %.4g V -> %.4g V at the card (x%g: %.4g..%.4g V at the "
               "piezo), %.3g s, %d steps\n",
               settings.axes > 1 ? (" axis " + std::string(axis_name(axis))).c_str() : "", center_V, hi_V, lo_V,
               center_V, c.amplifier_gain_V_per_V, lo_V * c.amplifier_gain_V_per_V, hi_V * c.amplifier_gain_V_per_V,
               o.duration_s, static_cast<int>(o.duration_s * o.rate_hz));
  const int steps = std::max(4, static_cast<int>(o.duration_s * o.rate_hz));
  std::vector<double> command_V, sensor_V;
  command_V.reserve(static_cast<std::size_t>(steps));
  sensor_V.reserve(static_cast<std::size_t>(steps));
  int faults = 0;
  const std::array<double, kMaxAxes> safe_V = settings.safe_voltages();
  std::array<double, kMaxAxes> u_V = safe_V;
  std::array<StageReading, kMaxAxes> readings{};
  const auto period = std::chrono::duration<double>(1.0 / o.rate_hz);
  auto next = std::chrono::steady_clock::now();
  backend.set_output_enabled(true);  // the amplifier enable (comedi.enable), for the drive only
  for (int i = 0; i <= steps; ++i) {
    const double t = triangle(static_cast<double>(i) / steps);
    const double card_V = std::clamp(center_V + t * o.amplitude_V, lo_V, hi_V);
    u_V[at] = card_V * c.amplifier_gain_V_per_V;
    backend.step_axes(std::span<const double>(u_V).first(n), i / o.rate_hz, 1.0 / o.rate_hz,
                      std::span(readings).first(n));
    const StageReading& r = readings[at];
    if ((r.flags & sample_flags::kSensorFault) != 0) {
      ++faults;
    } else {
      command_V.push_back(card_V);
      sensor_V.push_back((r.y_m - c.sensor_offset_m) / c.sensor_scale_m_per_V);
    }
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    std::this_thread::sleep_until(next);
  }
  backend.hold_safe(std::span<const double>(safe_V).first(n));
  const ProbeFit f = fit(command_V, sensor_V, faults);
  std::fprintf(out, "back at the safe %g V (%.4g V at the card)\n", a.safe_u_V, center_V);
  std::fprintf(out, "measured: sensor %+.4g V per V at the card (offset %+.4g V, r %.4f) over %d samples, %d faulted\n",
               f.gain_V_per_V, f.offset_V, f.r, f.samples, f.faults);
  const double m_per_V = f.gain_V_per_V * c.sensor_scale_m_per_V / c.amplifier_gain_V_per_V;
  const std::string scale_key = axis_field("comedi.sensor.scale_m_per_V", axis);
  std::fprintf(out, "  = %+.4g m per V at the piezo with %s %g and %s %g (%s is %g)\n", m_per_V, scale_key.c_str(),
               c.sensor_scale_m_per_V, axis_field("comedi.amplifier_gain_V_per_V", axis).c_str(),
               c.amplifier_gain_V_per_V, axis_field("servo.nominal_gain_m_per_V", axis).c_str(),
               settings.servo_of(axis).nominal_gain_m_per_V);
  if (f.samples < 3 || std::abs(f.r) < 0.9) {
    std::fprintf(out,
                 "verdict: NO CLEAR RESPONSE (|r| < 0.9 or too few good reads): check the wiring, %s* "
                 "and the amplifier's enable before running the loop\n",
                 axis_field("comedi.ai.", axis).c_str());
    return 1;
  }
  if (m_per_V < 0) {
    std::fprintf(out,
                 "verdict: SIGN REVERSED: the position falls as the command rises; swap the sensor's wiring or "
                 "negate %s\n",
                 scale_key.c_str());
    return 1;
  }
  std::fprintf(out, "verdict: sign OK (position rises with the command)\n");
  return 0;
}

}  // namespace

int probe_hardware(const BridgeSettings& settings, const ProbeOptions& options, std::FILE* out) {
  const ComediSettings& card = settings.comedi;
  try {
    if (options.axis < 0 || options.axis >= settings.axes) {
      throw ParameterError("--axis",
                           fmt::format("the stage has {} ax{} (bridge.axes): there is no axis {}", settings.axes,
                                       settings.axes == 1 ? "is" : "es", axis_name(options.axis)));
    }
    {
      const ComediHandle handle(card.device, card.calibration, card.source);
      std::fprintf(out, "device: %s\n", card.device.c_str());
      list_card(handle, out);
    }
    if (!options.drive) {
      const ComediAxisSettings& c = card.axis(options.axis);
      const ActuatorLimits& a = settings.limits_of(options.axis);
      const std::string which = settings.axes > 1 ? fmt::format(" axis {}'s", axis_name(options.axis)) : std::string();
      std::fprintf(out,
                   "not driving the output. With --yes, hystloop-bridge would write the safe %g V (%.4g V at the card) "
                   "to%s ao subdevice %s channel %d range %d%s, then a triangle of +-%g V at the card around it for "
                   "%g s (clamped to %s..%s = [%g, %g] V at the piezo and the DAC's range), read ai subdevice %s "
                   "channel %d range %d aref %s at every step, return to the safe voltage and report the sensor's "
                   "gain and sign. The amplifier must be enabled and the stage free to move.\n",
                   a.safe_u_V, c.card_V(a.safe_u_V), which.c_str(),
                   c.ao.subdevice < 0 ? "auto" : std::to_string(c.ao.subdevice).c_str(), c.ao.channel, c.ao.range,
                   settings.axes > 1 ? " (every other axis held at its safe voltage)" : "", options.amplitude_V,
                   options.duration_s, axis_field("actuator.u_min_V", options.axis).c_str(),
                   axis_field("actuator.u_max_V", options.axis).c_str(), a.u_min_V, a.u_max_V,
                   c.ai.subdevice < 0 ? "auto" : std::to_string(c.ai.subdevice).c_str(), c.ai.channel, c.ai.range,
                   aref_name(c.ai.aref));
      return 0;
    }
    return drive(settings, options, out);
  } catch (const ParameterError& e) {
    std::fprintf(out, "refused: %s\n", e.what());
    return kExitUsage;
  } catch (const std::exception& e) {
    std::fprintf(out, "failed: %s\n", e.what());
    return 1;
  }
}

}  // namespace hystloop
