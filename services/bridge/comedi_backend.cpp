#include "bridge/comedi_backend.hpp"

#include <signal.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include "core/config.hpp"

namespace hystloop {
namespace {

// The live backend, for the fatal-signal and terminate handlers (one card per process).
std::atomic<ComediBackend*> g_live{nullptr};
std::terminate_handler g_previous_terminate = nullptr;

void write_stderr(const char* text) noexcept {
  std::size_t n = 0;
  while (text[n] != '\0') ++n;
  [[maybe_unused]] const ssize_t w = ::write(2, text, n);
}

void on_fatal_signal(int sig) {
  if (ComediBackend* b = g_live.load(); b != nullptr && b->emergency_safe()) {
    write_stderr(
        "hystloop-bridge: fatal signal: ramped the comedi outputs to the safe voltage, amplifier enable "
        "dropped\n");
  }
  ::signal(sig, SIG_DFL);  // SA_RESETHAND did it already; be sure
  ::raise(sig);
}

void on_terminate() {
  if (ComediBackend* b = g_live.load(); b != nullptr && b->emergency_safe()) {
    write_stderr(
        "hystloop-bridge: std::terminate: ramped the comedi outputs to the safe voltage, amplifier enable "
        "dropped\n");
  }
  if (g_previous_terminate != nullptr) g_previous_terminate();
  std::abort();
}

void install_emergency_handlers() {
  static bool installed = false;
  if (installed) return;
  installed = true;
  struct sigaction sa {};
  sa.sa_handler = on_fatal_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESETHAND | SA_NODEFER;
  for (const int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) ::sigaction(sig, &sa, nullptr);
  g_previous_terminate = std::set_terminate(on_terminate);
}

std::string comedi_error() { return comedi_strerror(comedi_errno()); }

void add_ns(timespec& t, long ns) noexcept {
  t.tv_nsec += ns;
  while (t.tv_nsec >= 1'000'000'000L) {
    t.tv_nsec -= 1'000'000'000L;
    ++t.tv_sec;
  }
}

// One write or read of `data` on a channel.
comedi_insn instruction(unsigned insn, lsampl_t* data, unsigned subdevice, const ComediChannelSettings& c) {
  comedi_insn i{};
  i.insn = insn;
  i.n = 1;
  i.data = data;
  i.subdev = subdevice;
  i.chanspec = CR_PACK(c.channel, c.range, c.aref);
  return i;
}

// settings.axes, when `limits` has an entry per axis.
int checked_axes(const ComediSettings& settings, std::span<const ActuatorLimits> limits) {
  if (settings.axes < 1 || settings.axes > kMaxAxes) {
    throw ParameterError("bridge.axes", fmt::format("must be 1..{} (got {})", kMaxAxes, settings.axes));
  }
  if (limits.size() != static_cast<std::size_t>(settings.axes)) {
    throw ParameterError("bridge.axes", fmt::format("the comedi backend drives {} axes but was given {} actuators' "
                                                    "limits",
                                                    settings.axes, limits.size()));
  }
  return settings.axes;
}

int find_subdevice(comedi_t* device, int configured, int type) {
  if (configured >= 0) return configured;
  for (int s = 0, n = comedi_get_n_subdevices(device); s < n; ++s) {
    if (comedi_get_subdevice_type(device, static_cast<unsigned>(s)) == type) return s;
  }
  return -1;
}

}  // namespace

ComediConverter::ComediConverter(comedi_t* device, unsigned subdevice, unsigned channel, unsigned range,
                                 const comedi_calibration_t* calibration) {
  const comedi_range* r = comedi_get_range(device, subdevice, channel, range);
  maxdata_ = comedi_get_maxdata(device, subdevice, channel);
  if (r == nullptr || maxdata_ == 0) throw std::runtime_error("no range table: " + comedi_error());
  range_ = *r;
  const int flags = comedi_get_subdevice_flags(device, subdevice);
  if (calibration != nullptr && flags >= 0 && (flags & SDF_SOFT_CALIBRATED) != 0) {
    softcal_ =
        comedi_get_softcal_converter(subdevice, channel, range, COMEDI_TO_PHYSICAL, calibration, &to_phys_) == 0 &&
        comedi_get_softcal_converter(subdevice, channel, range, COMEDI_FROM_PHYSICAL, calibration, &from_phys_) == 0;
  }
}

double ComediConverter::to_V(lsampl_t counts) const noexcept {
  if (softcal_) {
    if (counts == 0 || counts >= maxdata_) return std::nan("");  // the softcal path does not flag the ends
    return comedi_to_physical(counts, &to_phys_);
  }
  comedi_range r = range_;  // comedi_to_phys takes a non-const pointer
  return comedi_to_phys(counts, &r, maxdata_);
}

lsampl_t ComediConverter::from_V(double volts) const noexcept {
  if (softcal_) {
    const lsampl_t code = comedi_from_physical(volts, &from_phys_);
    return code > maxdata_ ? maxdata_ : code;
  }
  comedi_range r = range_;
  return comedi_from_phys(volts, &r, maxdata_);
}

std::string ComediConverter::describe() const {
  if (softcal_) {
    return fmt::format("[{:g}, {:g}] V, maxdata {}, softcal: to V {:.6g} + {:.6g}*(x-{:g}) (order {})", range_.min,
                       range_.max, maxdata_, to_phys_.coefficients[0], to_phys_.coefficients[1],
                       to_phys_.expansion_origin, to_phys_.order);
  }
  return fmt::format("[{:g}, {:g}] V, maxdata {}, range table (no softcal)", range_.min, range_.max, maxdata_);
}

ComediHandle::ComediHandle(const std::string& path, const std::string& calibration_setting, const std::string& source) {
  device = comedi_open(path.c_str());
  if (device == nullptr) throw std::runtime_error("comedi_open(" + path + "): " + comedi_error());
  if (calibration_setting == "none") return;
  if (calibration_setting == "auto") {
    if (char* p = comedi_get_default_calibration_path(device)) {
      calibration_path = p;
      std::free(p);
    }
  } else {
    calibration_path = calibration_setting;
  }
  if (!calibration_path.empty()) {
    calibration = comedi_parse_calibration_file(calibration_path.c_str());
    if (calibration == nullptr) {
      if (calibration_setting != "auto") {
        comedi_close(device);
        throw ConfigError(source, "comedi.calibration", "cannot parse '" + calibration_path + "'");
      }
      calibration_path.clear();  // auto: the board has no calibration file (or needs none)
    }
  }
}

ComediHandle::~ComediHandle() {
  if (calibration != nullptr) comedi_cleanup_calibration(calibration);
  if (device != nullptr) comedi_close(device);
}

ComediBackend::ComediBackend(const ComediSettings& settings, std::span<const ActuatorLimits> limits)
    : settings_(settings),
      axes_(checked_axes(settings, limits)),
      handle_(settings.device, settings.calibration, settings.source) {
  for (int i = 0; i < axes_; ++i) {
    Axis& a = axis_[static_cast<std::size_t>(i)];
    a.settings = settings_.axis(i);
    a.limits = limits[static_cast<std::size_t>(i)];
    u_held_V_[static_cast<std::size_t>(i)] = a.limits.safe_u_V;
  }
  check_against_card();  // writes the safe voltages of the usable outputs first, then throws
  prepare_enable();      // the same
  const auto n = static_cast<std::size_t>(axes_);
  std::size_t at = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Axis& a = axis_[i];
    tick_insns_[at++] = instruction(INSN_WRITE, &dac_words_[i], a.ao_subdevice, a.settings.ao);
    // The safe ramp's step in DAC counts: the actuator's rate through the amplifier, at least a count.
    const double counts_per_V = static_cast<double>(a.dac.maxdata()) / (a.dac.max_V() - a.dac.min_V());
    const double card_V = a.limits.safe_ramp_V_per_s * kRampTick_s / a.settings.amplifier_gain_V_per_V;
    ramp_step_[i] =
        static_cast<lsampl_t>(std::clamp(std::floor(card_V * counts_per_V), 1.0, static_cast<double>(a.dac.maxdata())));
  }
  if (settings_.enable.configured()) {
    enable_word_ = enable_idle_word_;
    tick_insns_[at++] = instruction(INSN_WRITE, &enable_word_, enable_subdevice_,
                                    ComediChannelSettings{settings_.enable.subdevice, settings_.enable.channel, 0, 0});
  }
  reads_at_ = at;
  for (std::size_t i = 0; i < n; ++i) {
    const Axis& a = axis_[i];
    tick_insns_[at++] = instruction(INSN_READ, &adc_words_[i], a.ai_subdevice, a.settings.ai);
  }
  tick_list_.n_insns = static_cast<unsigned>(at);
  tick_list_.insns = tick_insns_.data();
  write_safe({});  // before anything can arm
  g_live.store(this);
  install_emergency_handlers();
  for (const std::string& line : describe()) spdlog::info("{}", line);
  if (axes_ == 1) {
    spdlog::info("comedi: the safe {} V written (DAC code {})", axis_[0].limits.safe_u_V, safe_data_[0]);
  } else {
    std::string codes;
    for (std::size_t i = 0; i < n; ++i) {
      codes += fmt::format("{}{} {} V (DAC code {})", i == 0 ? "" : ", ", axis_name(static_cast<int>(i)),
                           axis_[i].limits.safe_u_V, safe_data_[i]);
    }
    spdlog::info("comedi: the safe voltages written: {}", codes);
  }
}

ComediBackend::~ComediBackend() {
  set_safe_codes({});  // each actuator's own
  ramp_to_safe();      // the last word (no ramp when the bridge's ended there)
  ComediBackend* self = this;
  g_live.compare_exchange_strong(self, nullptr);
}

void ComediBackend::prepare_safe_list(const std::array<bool, kMaxAxes>& usable) noexcept {
  unsigned n = 0;
  safe_axes_ = usable;
  for (std::size_t i = 0; i < static_cast<std::size_t>(axes_); ++i) {
    if (!usable[i]) continue;
    const Axis& a = axis_[i];
    ramp_insns_[n] = instruction(INSN_WRITE, &ramp_data_[i], a.ao_subdevice, a.settings.ao);
    safe_insns_[n++] = instruction(INSN_WRITE, &safe_data_[i], a.ao_subdevice, a.settings.ao);
  }
  safe_list_.n_insns = n;
  safe_list_.insns = n > 0 ? safe_insns_.data() : nullptr;
  ramp_list_.n_insns = n;
  ramp_list_.insns = n > 0 ? ramp_insns_.data() : nullptr;
}

void ComediBackend::prepare_enable() {
  const ComediEnableSettings& e = settings_.enable;
  if (!e.configured()) return;
  comedi_t* dev = handle_.device;
  const auto refuse = [&](const std::string& field, const std::string& reason) {
    write_safe({});
    throw ConfigError(settings_.source, field, fmt::format("{} ({})", reason, settings_.device));
  };
  int s = e.subdevice;
  if (s < 0) s = find_subdevice(dev, -1, COMEDI_SUBD_DIO);
  if (s < 0) s = find_subdevice(dev, -1, COMEDI_SUBD_DO);
  if (s < 0) refuse("comedi.enable.subdevice", "the card has no digital I/O or digital output subdevice");
  if (s >= comedi_get_n_subdevices(dev)) {
    refuse("comedi.enable.subdevice", fmt::format("the card has {} subdevices", comedi_get_n_subdevices(dev)));
  }
  const auto su = static_cast<unsigned>(s);
  const int type = comedi_get_subdevice_type(dev, su);
  if (type != COMEDI_SUBD_DIO && type != COMEDI_SUBD_DO) {
    refuse("comedi.enable.subdevice", fmt::format("subdevice {} is not a digital output", s));
  }
  if (const int channels = comedi_get_n_channels(dev, su); e.channel >= channels) {
    refuse("comedi.enable.channel", fmt::format("subdevice {} has {} channels", s, channels));
  }
  enable_subdevice_ = su;
  enable_idle_word_ = enable_level(false);
  // The latch first, then the direction: the line comes up inactive. Then once more, checked.
  comedi_insn idle = instruction(INSN_WRITE, &enable_idle_word_, su, ComediChannelSettings{s, e.channel, 0, 0});
  comedi_insnlist one{1, &idle};
  comedi_do_insnlist(dev, &one);
  if (type == COMEDI_SUBD_DIO && comedi_dio_config(dev, su, static_cast<unsigned>(e.channel), COMEDI_OUTPUT) < 0) {
    refuse("comedi.enable.channel",
           fmt::format("channel {} of subdevice {} cannot be made an output: {}", e.channel, s, comedi_error()));
  }
  if (comedi_do_insnlist(dev, &one) != 1) {
    refuse("comedi.enable.channel",
           fmt::format("the card refused a write to channel {} of subdevice {}: {}", e.channel, s, comedi_error()));
  }
  safe_insns_[safe_list_.n_insns++] = idle;
  ramp_insns_[ramp_list_.n_insns++] =
      instruction(INSN_WRITE, &ramp_enable_word_, su, ComediChannelSettings{s, e.channel, 0, 0});
}

void ComediBackend::check_against_card() {
  comedi_t* dev = handle_.device;
  const auto fail = [&](const std::string& field, const std::string& reason) {
    throw ConfigError(settings_.source, field, fmt::format("{} ({})", reason, settings_.device));
  };
  // Axis `axis`'s channel `c` (prefix "ao"/"ai"): its subdevice, checked; keys named as the file spells them.
  const auto check_channel = [&](int axis, const char* prefix, const ComediChannelSettings& c, int type,
                                 const char* kind) {
    const int s = find_subdevice(dev, c.subdevice, type);
    const std::string p = axis_field(std::string("comedi.") + prefix + ".", axis);
    if (s < 0) fail(p + "subdevice", fmt::format("the card has no {} subdevice", kind));
    if (s >= comedi_get_n_subdevices(dev))
      fail(p + "subdevice", fmt::format("the card has {} subdevices", comedi_get_n_subdevices(dev)));
    if (comedi_get_subdevice_type(dev, static_cast<unsigned>(s)) != type)
      fail(p + "subdevice", fmt::format("subdevice {} is not an {}", s, kind));
    const unsigned su = static_cast<unsigned>(s);
    const int n_channels = comedi_get_n_channels(dev, su);
    if (c.channel >= n_channels) fail(p + "channel", fmt::format("subdevice {} has {} channels", s, n_channels));
    const int n_ranges = comedi_get_n_ranges(dev, su, static_cast<unsigned>(c.channel));
    if (c.range >= n_ranges) fail(p + "range", fmt::format("channel {} has {} ranges", c.channel, n_ranges));
    const comedi_range* r = comedi_get_range(dev, su, static_cast<unsigned>(c.channel), static_cast<unsigned>(c.range));
    if (r == nullptr || r->unit != UNIT_volt) fail(p + "range", fmt::format("range {} is not in volts", c.range));
    const int flags = comedi_get_subdevice_flags(dev, su);
    const int aref_flags[] = {SDF_GROUND, SDF_COMMON, SDF_DIFF, SDF_OTHER};
    if (flags >= 0 && (flags & aref_flags[c.aref]) == 0 && type == COMEDI_SUBD_AI) {
      fail(p + "aref", fmt::format("subdevice {} cannot do aref {}", s, aref_name(c.aref)));
    }
    return su;
  };
  const auto n = static_cast<std::size_t>(axes_);
  // Every axis's output first: the ones usable are written their safe voltage before any refusal,
  // also when another axis's is not (the first refusal is thrown after that write).
  std::array<bool, kMaxAxes> usable{};
  std::optional<ConfigError> refused;
  for (std::size_t i = 0; i < n; ++i) {
    Axis& a = axis_[i];
    const int axis = static_cast<int>(i);
    try {
      a.ao_subdevice = check_channel(axis, "ao", a.settings.ao, COMEDI_SUBD_AO, "analog output");
      // The config compared the subdevices as written; here -1 is the one it stands for.
      for (std::size_t j = 0; j < i; ++j) {
        if (usable[j] && axis_[j].ao_subdevice == a.ao_subdevice &&
            axis_[j].settings.ao.channel == a.settings.ao.channel) {
          fail(axis_field("comedi.ao.channel", axis),
               fmt::format("axis {} drives ao subdevice {} channel {} already: two axes on one output would drive "
                           "one amplifier twice",
                           axis_name(static_cast<int>(j)), a.ao_subdevice, a.settings.ao.channel));
        }
      }
      try {
        a.dac = ComediConverter(dev, a.ao_subdevice, static_cast<unsigned>(a.settings.ao.channel),
                                static_cast<unsigned>(a.settings.ao.range), handle_.calibration);
      } catch (const std::runtime_error& e) {
        fail(axis_field("comedi.ao.range", axis), e.what());
      }
      usable[i] = true;
    } catch (const ConfigError& e) {
      if (!refused) refused = e;
    }
  }
  // From here the usable outputs are known: a refusal below leaves them at their safe voltages.
  prepare_safe_list(usable);
  const auto refuse = [&](const std::string& field, const std::string& reason) {
    write_safe({});
    fail(field, reason);
  };
  if (refused) {
    write_safe({});
    throw *refused;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Axis& a = axis_[i];
    const double lo_V = a.settings.card_V(a.limits.u_min_V), hi_V = a.settings.card_V(a.limits.u_max_V);
    if (lo_V < a.dac.min_V() || hi_V > a.dac.max_V()) {
      const int axis = static_cast<int>(i);
      refuse(axis_field("comedi.ao.range", axis),
             fmt::format("the DAC's [{:g}, {:g}] V does not cover {}..{} / {} = [{:g}, {:g}] V", a.dac.min_V(),
                         a.dac.max_V(), axis_field("actuator.u_min_V", axis), axis_field("actuator.u_max_V", axis),
                         axis_field("comedi.amplifier_gain_V_per_V", axis), lo_V, hi_V));
    }
  }
  try {
    for (std::size_t i = 0; i < n; ++i) {
      Axis& a = axis_[i];
      const int axis = static_cast<int>(i);
      a.ai_subdevice = check_channel(axis, "ai", a.settings.ai, COMEDI_SUBD_AI, "analog input");
      for (std::size_t j = 0; j < i; ++j) {
        if (axis_[j].ai_subdevice == a.ai_subdevice && axis_[j].settings.ai.channel == a.settings.ai.channel) {
          fail(axis_field("comedi.ai.channel", axis),
               fmt::format("axis {} reads ai subdevice {} channel {} already: each axis needs its own sensor's input",
                           axis_name(static_cast<int>(j)), a.ai_subdevice, a.settings.ai.channel));
        }
      }
      try {
        a.adc = ComediConverter(dev, a.ai_subdevice, static_cast<unsigned>(a.settings.ai.channel),
                                static_cast<unsigned>(a.settings.ai.range), handle_.calibration);
      } catch (const std::runtime_error& e) {
        fail(axis_field("comedi.ai.range", axis), e.what());
      }
    }
  } catch (const ConfigError&) {
    write_safe({});
    throw;
  }
}

lsampl_t ComediBackend::enable_at(bool active, double t_s) const noexcept {
  const ComediEnableSettings& e = settings_.enable;
  // A heartbeat is active for the first half of each period from t = 0: a pure function of the
  // time, so skipped ticks do not shift it.
  const bool second_half = e.heartbeat && static_cast<std::int64_t>(std::floor(t_s * 2.0 * e.heartbeat_hz)) % 2 != 0;
  return enable_level(active && !second_half);
}

lsampl_t ComediBackend::dac_code(int axis, double u_V) noexcept {
  const Axis& a = axis_[static_cast<std::size_t>(axis)];
  if (!(u_V >= a.limits.u_min_V)) u_V = a.limits.u_min_V;  // also NaN: the low end (BridgeCore never sends one)
  if (u_V > a.limits.u_max_V) u_V = a.limits.u_max_V;
  double v = a.settings.card_V(u_V);
  if (v < a.dac.min_V() || v > a.dac.max_V()) {
    counters_.dac_clamped.fetch_add(1, std::memory_order_relaxed);
    v = v < a.dac.min_V() ? a.dac.min_V() : a.dac.max_V();
  }
  return a.dac.from_V(v);
}

double ComediBackend::position_m(int axis, lsampl_t counts) const noexcept {
  const Axis& a = axis_[static_cast<std::size_t>(axis)];
  if (counts == 0 || counts >= a.adc.maxdata()) return std::nan("");
  return a.settings.position_m(a.adc.to_V(counts));
}

StageReading ComediBackend::step(double u_V, double t_s, double dt_s) noexcept {
  u_held_V_[0] = u_V;
  std::array<StageReading, kMaxAxes> out{};
  const auto n = static_cast<std::size_t>(axes_);
  step_axes(std::span<const double>(u_held_V_).first(n), t_s, dt_s, std::span(out).first(n));
  return out[0];
}

void ComediBackend::step_axes(std::span<const double> u_V, double t_s, double /*dt_s*/,
                              std::span<StageReading> out) noexcept {
  const auto n = static_cast<std::size_t>(axes_);
  for (std::size_t i = 0; i < n; ++i) {
    u_held_V_[i] = u_V[i];
    dac_words_[i] = dac_code(static_cast<int>(i), u_V[i]);
  }
  const ComediEnableSettings& e = settings_.enable;
  if (e.configured()) {
    enable_word_ = enable_at(enable_, t_s);
  }
  // Every write (the enable's last), then every read: comedi stops at the first instruction that
  // fails, so rc says which writes and which axes' reads happened.
  const int rc = comedi_do_insnlist(handle_.device, &tick_list_);
  counters_.transfers.fetch_add(1, std::memory_order_relaxed);
  const std::size_t done = rc > 0 ? static_cast<std::size_t>(rc) : 0;
  if (done < reads_at_) counters_.write_errors.fetch_add(reads_at_ - done, std::memory_order_relaxed);
  for (std::size_t i = 0; i < n && i < done; ++i) last_code_[i].store(dac_words_[i], std::memory_order_relaxed);
  if (e.configured() && done >= reads_at_ && enable_ != enable_active_.load(std::memory_order_relaxed)) {
    enable_active_.store(enable_, std::memory_order_relaxed);
    (enable_ ? counters_.enable_rises : counters_.enable_drops).fetch_add(1, std::memory_order_relaxed);
  }
  for (std::size_t i = 0; i < n; ++i) {
    Axis& a = axis_[i];
    bool fault = false;
    if (done < reads_at_ + i + 1) {
      fault = true;
      counters_.read_errors.fetch_add(1, std::memory_order_relaxed);
    } else {
      const double y = position_m(static_cast<int>(i), adc_words_[i]);
      if (std::isfinite(y)) {
        a.y_last_m = y;
      } else {
        fault = true;
        counters_.saturated.fetch_add(1, std::memory_order_relaxed);
      }
    }
    StageReading& r = out[i];
    r = StageReading{};  // y_true_m NaN: hardware cannot know it
    r.y_m = a.y_last_m;
    if (!fault) {
      a.consecutive_faults = 0;
      continue;
    }
    counters_.sensor_faults.fetch_add(1, std::memory_order_relaxed);
    counters_.axis_sensor_faults[i].fetch_add(1, std::memory_order_relaxed);
    r.flags = sample_flags::kSensorFault;
    if (++a.consecutive_faults >= settings_.fault_limit) {
      r.go_safe = true;
      if (a.consecutive_faults == settings_.fault_limit) {
        counters_.fault_safe.fetch_add(1, std::memory_order_relaxed);
        counters_.axis_fault_safe[i].fetch_add(1, std::memory_order_relaxed);
      }
    }
  }
}

void ComediBackend::hold_safe(std::span<const double> safe_u_V) noexcept {
  set_safe_codes(safe_u_V);
  for (std::size_t i = 0; i < static_cast<std::size_t>(axes_); ++i) {
    u_held_V_[i] = i < safe_u_V.size() ? safe_u_V[i] : axis_[i].limits.safe_u_V;
  }
  enable_ = false;
  ramp_to_safe();
}

void ComediBackend::set_safe_codes(std::span<const double> safe_u_V) noexcept {
  for (std::size_t i = 0; i < static_cast<std::size_t>(axes_); ++i) {
    if (!safe_axes_[i]) continue;
    safe_data_[i] = dac_code(static_cast<int>(i), i < safe_u_V.size() ? safe_u_V[i] : axis_[i].limits.safe_u_V);
  }
}

void ComediBackend::write_safe(std::span<const double> safe_u_V) noexcept {
  if (safe_list_.n_insns == 0) return;  // no usable output (a refusal before any)
  set_safe_codes(safe_u_V);
  for (std::size_t i = 0; i < static_cast<std::size_t>(axes_); ++i) {
    if (safe_axes_[i]) last_code_[i].store(safe_data_[i], std::memory_order_relaxed);
  }
  comedi_do_insnlist(handle_.device, &safe_list_);
  counters_.safe_writes.fetch_add(1, std::memory_order_relaxed);
}

bool ComediBackend::ramp_to_safe() noexcept {
  if (safe_list_.n_insns == 0) return false;  // no usable output (a refusal before any)
  const auto n = static_cast<std::size_t>(axes_);
  for (std::size_t i = 0; i < n; ++i) ramp_data_[i] = last_code_[i].load(std::memory_order_relaxed);
  timespec next{};
  ::clock_gettime(CLOCK_MONOTONIC, &next);
  const bool active = enable_active_.load(std::memory_order_relaxed);
  bool ramped = false;
  for (std::int64_t tick = 0;; ++tick) {
    bool there = true;
    for (std::size_t i = 0; i < n; ++i) {
      lsampl_t& c = ramp_data_[i];
      const lsampl_t target = safe_data_[i], step = ramp_step_[i];
      if (!safe_axes_[i] || c == target) continue;
      there = false;
      c = c < target ? (target - c > step ? c + step : target) : (c - target > step ? c - step : target);
    }
    if (there) break;
    ramped = true;
    ramp_enable_word_ = enable_at(active, static_cast<double>(tick) * kRampTick_s);
    comedi_do_insnlist(handle_.device, &ramp_list_);
    for (std::size_t i = 0; i < n; ++i) last_code_[i].store(ramp_data_[i], std::memory_order_relaxed);
    add_ns(next, static_cast<long>(kRampTick_s * 1e9));
    while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr) == EINTR) {
    }
  }
  if (ramped) counters_.safe_ramps.fetch_add(1, std::memory_order_relaxed);
  const bool taken = comedi_do_insnlist(handle_.device, &safe_list_) == static_cast<int>(safe_list_.n_insns);
  counters_.safe_writes.fetch_add(1, std::memory_order_relaxed);
  if (enable_active_.exchange(false, std::memory_order_relaxed)) {
    counters_.enable_drops.fetch_add(1, std::memory_order_relaxed);
  }
  return taken;
}

bool ComediBackend::emergency_safe() noexcept { return ramp_to_safe(); }

void ComediBackend::append_counters(std::vector<std::pair<std::string, std::uint64_t>>& entries) const {
  const auto add = [&](std::string name, const std::atomic<std::uint64_t>& v) {
    entries.emplace_back(std::move(name), v.load(std::memory_order_relaxed));
  };
  add("comedi_transfers", counters_.transfers);
  add("comedi_write_errors", counters_.write_errors);
  add("comedi_read_errors", counters_.read_errors);
  add("comedi_saturated", counters_.saturated);
  add("sensor_faults", counters_.sensor_faults);
  add("sensor_fault_safe", counters_.fault_safe);
  add("comedi_dac_clamped", counters_.dac_clamped);
  add("comedi_safe_writes", counters_.safe_writes);
  add("comedi_safe_ramps", counters_.safe_ramps);
  add("amp_enable_rises", counters_.enable_rises);
  add("amp_enable_drops", counters_.enable_drops);
  if (axes_ == 1) return;  // the totals are axis x's
  // Which axis's sensor fails, which one made the bridge go safe: x_sensor_faults, y_..., as the
  // bridge names its own per-axis counters (x_applied, ...).
  for (std::size_t i = 0; i < static_cast<std::size_t>(axes_); ++i) {
    const std::string p = std::string(axis_name(static_cast<int>(i))) + "_";
    add(p + "sensor_faults", counters_.axis_sensor_faults[i]);
    add(p + "sensor_fault_safe", counters_.axis_fault_safe[i]);
  }
}

std::vector<std::string> ComediBackend::describe() const {
  std::vector<std::string> lines;
  lines.push_back(fmt::format(
      "comedi {} ({} / {}): {} ax{}, calibration {}", settings_.device, comedi_get_driver_name(handle_.device),
      comedi_get_board_name(handle_.device), axes_, axes_ == 1 ? "is" : "es",
      handle_.calibration_path.empty() ? std::string("none (range tables)") : handle_.calibration_path));
  for (std::size_t i = 0; i < static_cast<std::size_t>(axes_); ++i) {
    const Axis& a = axis_[i];
    lines.push_back(fmt::format("comedi {}: ao subdevice {} channel {} {}; ai subdevice {} channel {} aref {} {}",
                                axis_name(static_cast<int>(i)), a.ao_subdevice, a.settings.ao.channel, a.dac.describe(),
                                a.ai_subdevice, a.settings.ai.channel, aref_name(a.settings.ai.aref),
                                a.adc.describe()));
  }
  const ComediEnableSettings& e = settings_.enable;
  lines.push_back(
      !e.configured()
          ? std::string("comedi enable: none (comedi.enable.channel -1)")
          : fmt::format("comedi enable: subdevice {} channel {}, {} active {}", enable_subdevice_, e.channel,
                        e.heartbeat ? fmt::format("a {:g} Hz heartbeat", e.heartbeat_hz) : std::string("a level"),
                        e.active_low ? "low" : "high"));
  return lines;
}

}  // namespace hystloop
