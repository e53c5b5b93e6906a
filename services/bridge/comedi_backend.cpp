#include "bridge/comedi_backend.hpp"

#include <signal.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <exception>
#include <stdexcept>

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
    write_stderr("hystloop-bridge: fatal signal: stepped the comedi output to the safe voltage\n");
  }
  ::signal(sig, SIG_DFL);  // SA_RESETHAND did it already; be sure
  ::raise(sig);
}

void on_terminate() {
  if (ComediBackend* b = g_live.load(); b != nullptr && b->emergency_safe()) {
    write_stderr("hystloop-bridge: std::terminate: stepped the comedi output to the safe voltage\n");
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

ComediBackend::ComediBackend(const ComediSettings& settings, const ActuatorLimits& limits)
    : settings_(settings), limits_(limits), handle_(settings.device, settings.calibration, settings.source) {
  check_against_card();  // writes the safe voltage first when the output is usable, then throws
  tick_insns_[0] = instruction(INSN_WRITE, &dac_word_, ao_subdevice_, settings_.ao);
  tick_insns_[1] = instruction(INSN_READ, &adc_word_, ai_subdevice_, settings_.ai);
  tick_list_.n_insns = 2;
  tick_list_.insns = tick_insns_;
  write_safe(limits_.safe_u_V);  // before anything can arm
  g_live.store(this);
  install_emergency_handlers();
  spdlog::info("{}; the safe {} V written (DAC code {})", describe(), limits_.safe_u_V, safe_data_);
}

ComediBackend::~ComediBackend() {
  write_safe(limits_.safe_u_V);  // the last word (a step: the bridge's ramp ended before, or could not run)
  ComediBackend* self = this;
  g_live.compare_exchange_strong(self, nullptr);
}

void ComediBackend::check_against_card() {
  comedi_t* dev = handle_.device;
  const auto fail = [&](const std::string& field, const std::string& reason) {
    throw ConfigError(settings_.source, field, fmt::format("{} ({})", reason, settings_.device));
  };
  const auto check_channel = [&](const char* prefix, const ComediChannelSettings& c, int type, const char* kind) {
    const int s = find_subdevice(dev, c.subdevice, type);
    const std::string p = std::string("comedi.") + prefix + ".";
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
  ao_subdevice_ = check_channel("ao", settings_.ao, COMEDI_SUBD_AO, "analog output");
  try {
    dac_ = ComediConverter(dev, ao_subdevice_, static_cast<unsigned>(settings_.ao.channel),
                           static_cast<unsigned>(settings_.ao.range), handle_.calibration);
  } catch (const std::runtime_error& e) {
    fail("comedi.ao.range", e.what());
  }
  // From here the output is usable: a refusal below leaves it at the safe voltage.
  safe_insn_ = instruction(INSN_WRITE, &safe_data_, ao_subdevice_, settings_.ao);
  safe_list_.n_insns = 1;
  safe_list_.insns = &safe_insn_;
  const auto refuse = [&](const std::string& field, const std::string& reason) {
    write_safe(limits_.safe_u_V);
    fail(field, reason);
  };
  const double lo_V = settings_.card_V(limits_.u_min_V), hi_V = settings_.card_V(limits_.u_max_V);
  if (lo_V < dac_.min_V() || hi_V > dac_.max_V()) {
    refuse("comedi.ao.range", fmt::format("the DAC's [{:g}, {:g}] V does not cover actuator.u_min_V..u_max_V / "
                                          "comedi.amplifier_gain_V_per_V = [{:g}, {:g}] V",
                                          dac_.min_V(), dac_.max_V(), lo_V, hi_V));
  }
  try {
    ai_subdevice_ = check_channel("ai", settings_.ai, COMEDI_SUBD_AI, "analog input");
    adc_ = ComediConverter(dev, ai_subdevice_, static_cast<unsigned>(settings_.ai.channel),
                           static_cast<unsigned>(settings_.ai.range), handle_.calibration);
  } catch (const ConfigError&) {
    write_safe(limits_.safe_u_V);
    throw;
  } catch (const std::runtime_error& e) {
    refuse("comedi.ai.range", e.what());
  }
}

lsampl_t ComediBackend::dac_code(double u_V) noexcept {
  if (!(u_V >= limits_.u_min_V)) u_V = limits_.u_min_V;  // also NaN: the low end (BridgeCore never sends one)
  if (u_V > limits_.u_max_V) u_V = limits_.u_max_V;
  double v = settings_.card_V(u_V);
  if (v < dac_.min_V() || v > dac_.max_V()) {
    counters_.dac_clamped.fetch_add(1, std::memory_order_relaxed);
    v = v < dac_.min_V() ? dac_.min_V() : dac_.max_V();
  }
  return dac_.from_V(v);
}

double ComediBackend::position_m(lsampl_t counts) const noexcept {
  if (counts == 0 || counts >= adc_.maxdata()) return std::nan("");
  return settings_.position_m(adc_.to_V(counts));
}

StageReading ComediBackend::step(double u_V, double /*t_s*/, double /*dt_s*/) noexcept {
  dac_word_ = dac_code(u_V);
  const int rc = comedi_do_insnlist(handle_.device, &tick_list_);
  counters_.transfers.fetch_add(1, std::memory_order_relaxed);
  bool fault = false;
  if (rc < 2) {
    fault = true;
    counters_.read_errors.fetch_add(1, std::memory_order_relaxed);
    if (rc < 1) counters_.write_errors.fetch_add(1, std::memory_order_relaxed);
  } else {
    const double y = position_m(adc_word_);
    if (std::isfinite(y)) {
      y_last_m_ = y;
    } else {
      fault = true;
      counters_.saturated.fetch_add(1, std::memory_order_relaxed);
    }
  }
  StageReading reading{y_last_m_, 0};
  if (!fault) {
    consecutive_faults_ = 0;
    return reading;
  }
  counters_.sensor_faults.fetch_add(1, std::memory_order_relaxed);
  reading.flags = sample_flags::kSensorFault;
  if (++consecutive_faults_ >= settings_.fault_limit) {
    reading.go_safe = true;
    if (consecutive_faults_ == settings_.fault_limit) counters_.fault_safe.fetch_add(1, std::memory_order_relaxed);
  }
  return reading;
}

void ComediBackend::hold_safe(std::span<const double> safe_u_V) noexcept { write_safe(safe_u_V[0]); }

void ComediBackend::write_safe(double safe_u_V) noexcept {
  safe_data_ = dac_code(safe_u_V);
  comedi_do_insnlist(handle_.device, &safe_list_);
  counters_.safe_writes.fetch_add(1, std::memory_order_relaxed);
}

bool ComediBackend::emergency_safe() noexcept {
  return safe_list_.insns != nullptr && comedi_do_insnlist(handle_.device, &safe_list_) == 1;
}

void ComediBackend::append_counters(std::vector<std::pair<std::string, std::uint64_t>>& entries) const {
  const auto add = [&](const char* name, const std::atomic<std::uint64_t>& v) {
    entries.emplace_back(name, v.load(std::memory_order_relaxed));
  };
  add("comedi_transfers", counters_.transfers);
  add("comedi_write_errors", counters_.write_errors);
  add("comedi_read_errors", counters_.read_errors);
  add("comedi_saturated", counters_.saturated);
  add("sensor_faults", counters_.sensor_faults);
  add("sensor_fault_safe", counters_.fault_safe);
  add("comedi_dac_clamped", counters_.dac_clamped);
  add("comedi_safe_writes", counters_.safe_writes);
}

std::string ComediBackend::describe() const {
  return fmt::format(
      "comedi {} ({} / {}): ao subdevice {} channel {} {}; ai subdevice {} channel {} aref {} {}; "
      "calibration {}",
      settings_.device, comedi_get_driver_name(handle_.device), comedi_get_board_name(handle_.device), ao_subdevice_,
      settings_.ao.channel, dac_.describe(), ai_subdevice_, settings_.ai.channel, aref_name(settings_.ai.aref),
      adc_.describe(),
      handle_.calibration_path.empty() ? std::string("none (range tables)") : handle_.calibration_path);
}

}  // namespace hystloop
