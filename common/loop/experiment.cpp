#include "loop/experiment.hpp"

#include <algorithm>
#include <cmath>
#include <charconv>
#include <numbers>
#include <string>

#include "core/errors.hpp"
#include "models/multisine.hpp"

namespace hystloop {
namespace {

std::string_view next_word(std::string_view& rest) {
  const std::size_t begin = rest.find_first_not_of(' ');
  if (begin == std::string_view::npos) {
    rest = {};
    return {};
  }
  rest.remove_prefix(begin);
  const std::size_t end = std::min(rest.find(' '), rest.size());
  const std::string_view word = rest.substr(0, end);
  rest.remove_prefix(end);
  return word;
}

[[noreturn]] void bad_word(std::string_view word, const std::string& why) {
  throw ParameterError("experiment", "multisine: '" + std::string(word) + "': " + why +
                                         " (words: f_min=HZ periods=P realisations=R seed=S amplitude=rms|peak "
                                         "lines=all|odd ramp=S)");
}

double number_of(std::string_view word, std::string_view value) {
  double v = 0.0;
  const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
  if (ec != std::errc() || end != value.data() + value.size() || !std::isfinite(v)) bad_word(word, "not a number");
  return v;
}

std::uint64_t count_of(std::string_view word, std::string_view value) {
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
  if (ec != std::errc() || end != value.data() + value.size()) bad_word(word, "not a whole number");
  return v;
}

MultisineExperiment parse_multisine(std::string_view rest) {
  MultisineExperiment ms;
  std::string seen = " ";
  bool has_f_min = false;
  for (std::string_view word = next_word(rest); !word.empty(); word = next_word(rest)) {
    const std::size_t eq = word.find('=');
    if (eq == std::string_view::npos || eq == 0) bad_word(word, "expected key=value");
    const std::string key(word.substr(0, eq));
    const std::string_view value = word.substr(eq + 1);
    if (seen.find(" " + key + " ") != std::string::npos) bad_word(word, "given twice");
    seen += key + " ";
    if (key == "f_min") {
      ms.f_min_hz = number_of(word, value);
      has_f_min = true;
    } else if (key == "periods") {
      ms.periods = count_of(word, value);
    } else if (key == "realisations") {
      ms.realisations = count_of(word, value);
    } else if (key == "seed") {
      ms.seed = count_of(word, value);
    } else if (key == "amplitude") {
      if (value != "rms" && value != "peak") bad_word(word, "rms or peak");
      ms.peak = value == "peak";
    } else if (key == "lines") {
      if (value != "all" && value != "odd") bad_word(word, "all or odd");
      ms.odd = value == "odd";
    } else if (key == "ramp") {
      ms.ramp_s = number_of(word, value);
      if (ms.ramp_s < 0.0) bad_word(word, "must be >= 0");
    } else {
      bad_word(word, "unknown key");
    }
  }
  if (!has_f_min) throw ParameterError("experiment", "multisine: f_min=HZ is required (the band's bottom)");
  return ms;
}

// 0 at j = 0, rising to 1 at j = length (raised cosine): a fade without a step or a kink.
double fade(std::size_t j, std::size_t length) noexcept {
  return 0.5 * (1.0 - std::cos(std::numbers::pi * static_cast<double>(j) / static_cast<double>(length)));
}

}  // namespace

void ExperimentSpec::validate() const {
  require_positive("experiment.amplitude_V", amplitude_V);
  require_finite("experiment.offset_V", offset_V);
  require_positive("experiment.frequency_hz", frequency_hz);
  require_positive("experiment.duration_s", duration_s);
  if (!multisine) return;
  require_positive("experiment.f_min", ms.f_min_hz);
  if (!(ms.f_min_hz < frequency_hz)) {
    throw ParameterError("experiment.f_min", "must be below f_max (the frequency, " + number_text(frequency_hz) +
                                                 " Hz), got " + number_text(ms.f_min_hz) + " Hz");
  }
  if (ms.periods < 3 || ms.periods > 10000) {
    throw ParameterError(
        "experiment.periods",
        "must be 3 .. 10000 (the first of each realisation is its transient), got " + std::to_string(ms.periods));
  }
  if (ms.realisations < 1 || ms.realisations > 1000) {
    throw ParameterError("experiment.realisations", "must be 1 .. 1000, got " + std::to_string(ms.realisations));
  }
  if (!std::isfinite(ms.ramp_s)) throw ParameterError("experiment.ramp", "must be finite");
}

ExperimentSpec make_experiment_spec(std::string_view kind, double amplitude_V, double offset_V, double frequency_hz,
                                    double duration_s) {
  ExperimentSpec spec{amplitude_V, offset_V, frequency_hz, duration_s, kind == "settle"};
  std::string_view rest = kind;
  if (next_word(rest) == "multisine") {
    spec.multisine = true;
    spec.ms = parse_multisine(rest);
  } else if (kind != "sine" && kind != "settle") {
    throw ParameterError("experiment", "'" + std::string(kind) +
                                           "' unknown (sine, settle: a sine identification skips, or "
                                           "multisine f_min=HZ ...)");
  }
  spec.validate();
  return spec;
}

std::string format_multisine_kind(const MultisineExperiment& ms) {
  const MultisineExperiment d;
  std::string s = "multisine f_min=" + number_text(ms.f_min_hz, 17);
  s += " periods=" + std::to_string(ms.periods) + " realisations=" + std::to_string(ms.realisations);
  if (ms.seed != d.seed) s += " seed=" + std::to_string(ms.seed);
  if (ms.peak) s += " amplitude=peak";
  if (ms.odd) s += " lines=odd";
  if (ms.ramp_s >= 0.0) s += " ramp=" + number_text(ms.ramp_s, 17);
  return s;
}

void prepare_experiment(ExperimentSpec& spec, double dt_s) {
  if (!spec.multisine) return;
  spec.validate();
  require_positive("dt", dt_s);
  const double ticks = spec.duration_s / dt_s;
  const auto n = static_cast<std::size_t>(std::llround(ticks));
  if (n < 4 || std::abs(ticks - static_cast<double>(n)) > 1e-6 * ticks) {
    throw ParameterError("experiment_duration_s", "a multisine's period (" + number_text(spec.duration_s) +
                                                      " s) must be a whole number of ticks (" + number_text(dt_s) +
                                                      " s), at least 4");
  }
  if (!(spec.frequency_hz < 0.5 / dt_s)) {
    throw ParameterError("experiment", "multisine: f_max " + number_text(spec.frequency_hz) +
                                           " Hz must be below half the tick rate (" + number_text(0.5 / dt_s) + " Hz)");
  }
  const std::size_t ramp = spec.ms.ramp_s < 0.0 ? n : static_cast<std::size_t>(std::llround(spec.ms.ramp_s / dt_s));
  const double record = static_cast<double>(n) * static_cast<double>(spec.ms.periods * spec.ms.realisations);
  if (record + 2.0 * static_cast<double>(ramp) > static_cast<double>(kMaxMultisineSamples)) {
    throw ParameterError("experiment", "multisine: " + number_text(record + 2.0 * static_cast<double>(ramp)) +
                                           " ticks with its ramps, above the " + std::to_string(kMaxMultisineSamples) +
                                           " a compensator holds (fewer periods, realisations or a shorter period)");
  }
  MultisineOptions o;
  o.sample_rate_Hz = 1.0 / dt_s;
  o.period_samples = n;
  o.f_min_Hz = spec.ms.f_min_hz;
  o.f_max_Hz = spec.frequency_hz;
  o.lines = spec.ms.odd ? MultisineLines::odd : MultisineLines::all;
  o.amplitude_mode = spec.ms.peak ? MultisineAmplitude::peak : MultisineAmplitude::rms;
  o.amplitude_V = spec.amplitude_V;
  o.offset_V = spec.offset_V;
  o.periods = spec.ms.periods;
  o.realisations = spec.ms.realisations;
  o.seed = spec.ms.seed;
  Multisine m;
  try {
    m = design_multisine(o);
  } catch (const ParameterError& e) {
    throw ParameterError("experiment", std::string("multisine: ") + e.what());
  }
  auto out = std::make_shared<MultisineSamples>();
  out->dt_s = dt_s;
  out->period_samples = n;
  out->ramp_samples = ramp;
  out->record_samples = m.u_V.size();
  out->lines = m.lines;
  const std::size_t pn = spec.ms.periods * n;
  // Realisation r's periodic signal about the offset at sample j of a period.
  auto periodic = [&](std::size_t r, std::size_t j) { return m.u_V[r * pn + j % n] - spec.offset_V; };
  out->u_V.reserve(out->record_samples + 2 * ramp);
  for (std::size_t j = 0; j < ramp; ++j) {
    out->u_V.push_back(spec.offset_V + fade(j, ramp) * periodic(0, (j + n - ramp % n) % n));
  }
  for (std::size_t k = 0; k < m.u_V.size(); ++k) {
    const std::size_t r = k / pn, j = k % pn;
    double u = m.u_V[k];
    if (r > 0 && j < n) {  // the transient period: fade from the previous realisation's phases
      const double w = fade(j, n);
      u = spec.offset_V + w * periodic(r, j) + (1.0 - w) * periodic(r - 1, j);
    }
    out->u_V.push_back(u);
  }
  const std::size_t last = spec.ms.realisations - 1;
  for (std::size_t j = 0; j < ramp; ++j) {
    out->u_V.push_back(spec.offset_V + (1.0 - fade(j + 1, ramp)) * periodic(last, j));
  }
  spec.samples = std::move(out);
}

double experiment_voltage(const ExperimentSpec& spec, double t_s) noexcept {
  if (spec.multisine) {
    if (!spec.samples || !(t_s >= 0.0)) return spec.offset_V;
    const auto k = static_cast<std::size_t>(std::llround(t_s / spec.samples->dt_s));
    return k < spec.samples->u_V.size() ? spec.samples->u_V[k] : spec.offset_V;
  }
  return spec.offset_V + spec.amplitude_V * std::sin(2.0 * std::numbers::pi * spec.frequency_hz * t_s);
}

double experiment_end_s(double start_s, const ExperimentSpec& spec) noexcept {
  if (spec.multisine) {
    if (!spec.samples) return start_s;
    // A tick that rounding lets in at the end reads past the samples: the offset, where the ramp ended.
    return start_s + static_cast<double>(spec.samples->u_V.size()) * spec.samples->dt_s;
  }
  const double periods = std::ceil(spec.duration_s * spec.frequency_hz - 1e-9);
  return start_s + periods / spec.frequency_hz;
}

std::int64_t first_tick_at_or_after(double t_s, double dt_s) noexcept {
  auto k = static_cast<std::int64_t>(std::ceil(t_s / dt_s));
  // The compensator compares static_cast<double>(k) * dt with t: settle the rounding the same way.
  while (k > 0 && static_cast<double>(k - 1) * dt_s >= t_s) --k;
  while (static_cast<double>(k) * dt_s < t_s) ++k;
  return k;
}

std::vector<ExperimentTicks> experiment_schedule(std::int64_t first_tick, std::span<const ExperimentSpec> specs,
                                                 double dt_s) {
  std::vector<ExperimentTicks> ticks;
  ticks.reserve(specs.size());
  double start_s = static_cast<double>(first_tick) * dt_s;  // Compensator::loop_time
  std::int64_t begin = first_tick;
  for (const ExperimentSpec& spec : specs) {
    const double end_s = experiment_end_s(start_s, spec);
    const std::int64_t end = std::max(begin, first_tick_at_or_after(end_s, dt_s));
    ticks.push_back({begin, end});
    begin = end;
    start_s = end_s;
  }
  return ticks;
}

}  // namespace hystloop
