#include "identify_stage.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include "core/cli.hpp"
#include "core/config.hpp"
#include "core/errors.hpp"
#include "ident/sample_csv.hpp"
#include "ident/stage_hysteresis_fit.hpp"
#include "ident/stage_identification.hpp"
#include "identify_output.hpp"
#include "log_samples.hpp"
#include "loop/compensator_config.hpp"
#include "loop/servo_notches.hpp"
#include "runtime/stage_config.hpp"
#include "models/csv_columns.hpp"
#include "models/multisine.hpp"
#include "plot_series.hpp"  // tools/report: write_text_file
#include "plots.hpp"

namespace hystloop {
namespace {

namespace fs = std::filesystem;
using C = std::complex<double>;

struct StageRecord {
  std::vector<double> u, y;  // R P N samples in design_multisine's layout
  double sample_rate_Hz = 0.0;
  std::size_t period_samples = 0, periods = 0, realisations = 0;
  std::vector<std::size_t> lines;
  std::string source;  // what the layout came from, for the output
};

std::string num(double v, int digits = 6) { return std::isfinite(v) ? number_text(v, digits) : "NaN"; }

std::pair<double, double> parse_band(const std::string& band) {
  const std::size_t colon = band.find(':');
  auto number = [&](std::string_view t) {
    double v = 0.0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (t.empty() || ec != std::errc() || end != t.data() + t.size() || !(v > 0.0)) {
      throw ParameterError("band", "expected F_MIN:F_MAX in Hz, both > 0 (got '" + band + "')");
    }
    return v;
  };
  if (colon == std::string::npos) number({});
  return {number(std::string_view(band).substr(0, colon)), number(std::string_view(band).substr(colon + 1))};
}

// The lines u excites: one steady period of the first realisation (averaged over its used
// periods), every line with at least a tenth of the largest amplitude.
std::vector<std::size_t> excited_lines(const StageRecord& r, std::size_t transient) {
  const std::size_t n = r.period_samples;
  std::vector<double> mean(n, 0.0);
  const std::size_t used = r.periods - transient;
  for (std::size_t p = transient; p < r.periods; ++p) {
    for (std::size_t j = 0; j < n; ++j) mean[j] += r.u[p * n + j] / static_cast<double>(used);
  }
  std::vector<double> amp(n / 2, 0.0);
  for (std::size_t k = 1; k < (n + 1) / 2; ++k) {
    C x = 0.0;
    for (std::size_t j = 0; j < n; ++j) {
      x += mean[j] *
           std::polar(1.0, -2.0 * std::numbers::pi * static_cast<double>((k * j) % n) / static_cast<double>(n));
    }
    amp[k] = std::abs(x);
  }
  double top = 0.0;
  for (const double a : amp) top = std::max(top, a);
  std::vector<std::size_t> lines;
  for (std::size_t k = 1; k < amp.size(); ++k) {
    if (amp[k] >= 0.1 * top && top > 0.0) lines.push_back(k);
  }
  return lines;
}

// A CSV: t,u,y (sample rate from t unless given) or u,y (--sample-rate).
StageRecord read_csv_record(const IdentifyArgs& args) {
  const std::string& file = args.files.front();
  std::ifstream in(file);
  if (!in) throw CsvError(file, 0, "cannot open the file");
  static constexpr std::array<std::string_view, 2> kUy{"u", "y"};
  CsvColumns c = read_csv_columns(in, file, kUy, {.any_case = true, .text_column = {}});
  StageRecord r;
  const bool has_t =
      std::any_of(c.ignored.begin(), c.ignored.end(), [](const std::string& n) { return n == "t" || n == "T"; });
  if (args.sample_rate_Hz) {
    r.sample_rate_Hz = *args.sample_rate_Hz;
  } else if (has_t) {
    std::ifstream again(file);
    static constexpr std::array<std::string_view, 1> kT{"t"};
    const CsvColumns t = read_csv_columns(again, file, kT, {.any_case = true, .text_column = {}});
    r.sample_rate_Hz = sample_rate_Hz(t.values[0]);
  }
  if (!(r.sample_rate_Hz > 0.0)) {
    throw ParameterError("sample-rate", file + " has no t column (or t does not increase): give --sample-rate");
  }
  if (args.period_samples == 0 || args.periods == 0) {
    throw ParameterError("period-samples",
                         "a CSV's multisine layout: give --period-samples N and --periods P "
                         "(and --realisations R, --skip S)");
  }
  r.period_samples = args.period_samples;
  r.periods = args.periods;
  r.realisations = std::max<std::size_t>(1, args.realisations);
  const std::size_t need = args.skip_samples + r.period_samples * r.periods * r.realisations;
  if (c.rows() < need) {
    throw ParameterError("periods", file + " holds " + std::to_string(c.rows()) + " samples; the layout needs " +
                                        std::to_string(need) + " (--skip + N P R)");
  }
  const auto begin = static_cast<std::ptrdiff_t>(args.skip_samples);
  const auto end = static_cast<std::ptrdiff_t>(need);
  r.u.assign(c.values[0].begin() + begin, c.values[0].begin() + end);
  r.y.assign(c.values[1].begin() + begin, c.values[1].begin() + end);
  r.source = file + ": N " + std::to_string(r.period_samples) + ", P " + std::to_string(r.periods) + ", R " +
             std::to_string(r.realisations) + " from the command line, " + num(r.sample_rate_Hz) + " Hz";
  return r;
}

// A log: the compensator's multisine experiment (--experiment N, or the only one).
StageRecord read_log_record(const IdentifyArgs& args, const ExperimentLogOptions& o) {
  LoggedExperiments logged = read_logged_experiments(args.files, o);
  std::cout << describe(logged);
  std::vector<std::size_t> multisines;
  for (std::size_t i = 0; i < logged.experiments.size(); ++i) {
    if (logged.experiments[i].spec.multisine) multisines.push_back(i);
  }
  std::size_t pick = 0;
  if (args.experiment) {
    pick = *args.experiment;
    if (pick >= logged.experiments.size() || !logged.experiments[pick].spec.multisine) {
      throw SampleLogError("--experiment " + std::to_string(pick) + ": not a multisine experiment of the log");
    }
  } else if (multisines.size() == 1) {
    pick = multisines.front();
  } else {
    throw SampleLogError(std::to_string(multisines.size()) +
                         " multisine experiments in the log: choose one with --experiment N (numbered as listed)");
  }
  LoggedExperiment& e = logged.experiments[pick];
  if (!e.usable()) throw SampleLogError("experiment " + std::to_string(pick) + " cannot be used: " + e.problem);
  const MultisineSamples& m = *e.spec.samples;
  StageRecord r;
  r.sample_rate_Hz = args.sample_rate_Hz.value_or(1.0 / o.dt_s);
  r.period_samples = m.period_samples;
  r.periods = e.spec.ms.periods;
  r.realisations = e.spec.ms.realisations;
  r.lines = m.lines;
  if (e.samples.u.size() < m.ramp_samples + m.record_samples) {
    throw SampleLogError("experiment " + std::to_string(pick) + ": " + std::to_string(e.samples.u.size()) +
                         " samples, fewer than its record");
  }
  const auto begin = static_cast<std::ptrdiff_t>(m.ramp_samples);
  const auto end = static_cast<std::ptrdiff_t>(m.ramp_samples + m.record_samples);
  r.u.assign(e.samples.u.begin() + begin, e.samples.u.begin() + end);
  r.y.assign(e.samples.y.begin() + begin, e.samples.y.begin() + end);
  r.source = "experiment " + std::to_string(pick) + " (request " + std::to_string(e.request_id) + "): N " +
             std::to_string(r.period_samples) + ", P " + std::to_string(r.periods) + ", R " +
             std::to_string(r.realisations) + ", " + std::to_string(r.lines.size()) + " lines, " +
             num(r.sample_rate_Hz) + " Hz";
  return r;
}

std::vector<double> unwrapped_deg(const std::vector<C>& g) {
  std::vector<double> out;
  double previous = 0.0, offset = 0.0;
  for (std::size_t i = 0; i < g.size(); ++i) {
    const double a = std::arg(g[i]);
    if (i > 0) {
      while (a + offset - previous > std::numbers::pi) offset -= 2.0 * std::numbers::pi;
      while (a + offset - previous < -std::numbers::pi) offset += 2.0 * std::numbers::pi;
    }
    previous = a + offset;
    out.push_back(previous * 180.0 / std::numbers::pi);
  }
  return out;
}

std::string roots_yaml(const std::vector<C>& roots_hz) {
  std::string s = "[";
  for (std::size_t i = 0; i < roots_hz.size(); ++i) {
    s += (i ? ", [" : "[") + num(roots_hz[i].real(), 10) + ", " + num(roots_hz[i].imag(), 10) + "]";
  }
  return s + "]";
}

// The fitted stage in the compensator's form (unit DC gain, the fitted delay).
LinearStageSpec fitted_spec(const StageFitResult& fit) {
  const auto roots = [](const std::vector<C>& rad_s) {
    std::vector<LinearStageSpec::Root> out;
    for (const C hz : roots_hz_once(rad_s)) out.push_back({hz.real(), hz.imag()});
    return out;
  };
  return LinearStageSpec::zero_pole(roots(fit.zeros_rad_s), roots(fit.poles_rad_s), fit.delay_s);
}

// The servo for the fitted stage (loop/servo_notches.hpp: its notches and integral gain), at the
// record's rate, the fitted delay taken as the loop's (a record of the live loop holds the card's
// read after write). No servo, with the reason, when the model is one the stage model refuses.
struct FittedServo {
  std::optional<StageServo> servo;
  std::string why;
};
FittedServo fitted_servo(const StageRecord& r, const StageFitResult& fit) {
  FeedbackGains base;
  base.tick_rate_hz = r.sample_rate_Hz;
  try {
    return {servo_for_stage(fitted_spec(fit), base), {}};
  } catch (const ParameterError& e) {
    return {std::nullopt, e.what()};
  }
}

std::string stage_yaml(const StageRecord& r, const FrequencyResponse& frf, const StageFitResult& fit, double dc_gain,
                       const std::string& heading, double known_to_hz, const FittedServo& fitted) {
  std::ostringstream y;
  y << "# hystloop-identify --model stage: " << heading << "\n"
    << "# " << r.source << "\n"
    << "# " << frf.frequency_Hz.size() << " lines " << num(frf.frequency_Hz.front()) << " .. "
    << num(frf.frequency_Hz.back()) << " Hz, " << frf.periods_used << " periods used x " << frf.realisations
    << " realisations; distortion ratio (sigma_total^2 / sigma_noise^2) " << num(frf.distortion_ratio, 3) << "\n"
    << "# measured DC gain u -> y: " << num(dc_gain, 8)
    << " per V (the hysteresis model carries it: the stage below has unit DC gain)\n"
    << "# model: orders " << fit.numerator_order << "/" << fit.denominator_order
    << (fit.zoh_sample_rate_Hz > 0.0 ? ", exact zero-order hold at " + num(fit.zoh_sample_rate_Hz) + " Hz"
                                     : ", continuous")
    << "; chi2 per line " << num(fit.chi2_per_line, 4) << " (expected " << num(fit.chi2_expected, 4) << ")"
    << (fit.order_consistent ? "" : ": NOT explained by the uncertainty") << "\n";
  if (!fit.orders.empty()) {
    y << "# orders tried (numerator/denominator: chi2 per line):";
    for (const StageOrderTrial& t : fit.orders) {
      y << " " << t.numerator_order << "/" << t.denominator_order << ": " << num(t.chi2_per_line, 4)
        << (t.accepted ? " (accepted)" : "");
    }
    y << "\n";
  }
  y << "stage:\n"
    << "  kind: linear\n"
    << "  zeros_hz: " << roots_yaml(roots_hz_once(fit.zeros_rad_s)) << "\n"
    << "  poles_hz: " << roots_yaml(roots_hz_once(fit.poles_rad_s)) << "\n"
    << "  delay_s: " << num(fit.delay_s, 8) << "\n"
    << "  known_to_hz: " << num(known_to_hz, 6) << "   # the model within " << num(100.0 * kStageKnownWithin, 3)
    << " % of the record (+2 sigma) up to here: learning may go to " << num(100.0 * kLearningShareOfKnownBand, 3)
    << " % of it\n";
  const std::vector<ModeNotch> notches = fitted.servo ? fitted.servo->notches : std::vector<ModeNotch>{};
  y << "# servo notches for this stage (the bridge's servo: section; check the gains' margins with\n"
    << "# hystloop-ctl gains --stage-config on this file):";
  if (notches.empty()) y << " none (no lightly damped mode lifts the gain)";
  y << "\n";
  for (std::size_t i = 0; i < notches.size(); ++i) {
    const ModeNotch& n = notches[i];
    const std::string key = i == 0 ? "notch" : "notch2";
    y << "#   " << key << "_hz: " << num(n.notch.hz, 6) << "   " << key << "_q: " << num(n.notch.q, 3)
      << "   # mode damping " << num(n.damping, 3) << ", " << num(n.peak_gain, 3) << " x the DC gain there\n";
  }
  if (const std::optional<StageServo>& servo = fitted.servo; servo && servo->gains.ki > 0.0) {
    y << "#   kp: 0   ki: " << num(servo->gains.ki, 6) << "   # margins " << num(servo->worst.gain_margin_dB, 3)
      << " dB / " << num(servo->worst.phase_margin_deg, 3) << " deg at the hysteresis' slope 0.6-1.4 of nominal\n";
  }
  return y.str();
}

void print_fit(const FrequencyResponse& frf, const StageFitResult& fit, double dc_gain) {
  std::printf("FRF: %zu lines %.6g .. %.6g Hz, %zu periods used x %zu realisations, distortion ratio %.3g\n",
              frf.frequency_Hz.size(), frf.frequency_Hz.front(), frf.frequency_Hz.back(), frf.periods_used,
              frf.realisations, frf.distortion_ratio);
  if (!fit.orders.empty()) {
    std::printf("  order  chi2/line  accepted\n");
    for (const StageOrderTrial& t : fit.orders) {
      std::printf("  %2d/%-2d  %9.4g  %s\n", t.numerator_order, t.denominator_order, t.chi2_per_line,
                  t.accepted ? "yes" : "no");
    }
  }
  std::printf("stage model: orders %d/%d, delay %.6g s, chi2 per line %.4g (expected %.4g)%s\n", fit.numerator_order,
              fit.denominator_order, fit.delay_s, fit.chi2_per_line, fit.chi2_expected,
              fit.order_consistent ? "" : " -- not explained by the uncertainty");
  std::printf("measured DC gain u -> y: %.8g per V (carried by the hysteresis model)\n", dc_gain);
  for (const C p : fit.poles_rad_s) {
    if (p.imag() < 0.0) continue;
    const double w = std::abs(p);
    std::printf("  pole %.6g Hz, damping %.4g\n", w / (2.0 * std::numbers::pi), -p.real() / w);
  }
}

void print_servo(const FittedServo& fitted) {
  const std::optional<StageServo>& servo = fitted.servo;
  if (!servo) {
    std::printf("servo: none suggested (%s)\n", fitted.why.c_str());
    return;
  }
  const std::vector<ModeNotch>& notches = servo->notches;
  if (notches.empty()) std::printf("servo notches: none (no lightly damped mode lifts the gain)\n");
  std::string args;
  for (std::size_t i = 0; i < notches.size(); ++i) {
    const ModeNotch& n = notches[i];
    std::printf("servo notch %zu: %.6g Hz, Q %.3g (mode damping %.3g, %.3g x the DC gain there)\n", i + 1, n.notch.hz,
                n.notch.q, n.damping, n.peak_gain);
    const std::string flag = i == 0 ? "--notch" : "--notch2";
    char buf[96];
    std::snprintf(buf, sizeof buf, " %s-hz %.6g %s-q %.3g", flag.c_str(), n.notch.hz, flag.c_str(), n.notch.q);
    args += buf;
  }
  if (notches.size() < kServoNotches) args += notches.empty() ? " --notch-hz 0 --notch2-hz 0" : " --notch2-hz 0";
  if (servo->gains.ki > 0.0) {
    std::printf(
        "servo gains: kp 0, ki %.0f 1/s: margins %.3g dB / %.3g deg at the hysteresis' slope 0.6-1.4 of nominal "
        "(designed for %g dB / %g deg)\n",
        servo->gains.ki, servo->worst.gain_margin_dB, servo->worst.phase_margin_deg, kServoDesignGainMargin_dB,
        kServoDesignPhaseMargin_deg);
    std::printf(
        "  set them: hystloop-ctl gains --kp 0 --ki %.0f --kd 0%s --stage-config THIS_YAML (prints the margins "
        "first)\n",
        servo->gains.ki, args.c_str());
  } else {
    std::printf("servo gains: no integral gain keeps %g dB / %g deg on this model\n", kServoDesignGainMargin_dB,
                kServoDesignPhaseMargin_deg);
    if (!notches.empty()) std::printf("  the notches: hystloop-ctl gains%s --stage-config THIS_YAML\n", args.c_str());
  }
}

// The fitted model against the stage a simulated record came from: the continuous models at unit
// DC gain, their worst magnitude and phase error over the lines up to `to_Hz`; and the lines where
// the true stage, as the bridge samples it (discretise(); one tick later where the record's y_k is
// the end of tick k, as the FRF was fitted: ident/stage_identification.hpp), lies inside the
// measured +-2 sigma_total. 0 when it was read; 2 for a file without a linear stage.
int compare_with_true_stage(const StageRecord& r, const FrequencyResponse& frf, const StageFitResult& fit,
                            const IdentifyArgs& args) {
  const std::string& file = args.true_stage;
  const Config config = Config::load_file(file);
  const char* prefix = nullptr;
  for (const char* p : {"plant.stage", "stage"}) {
    for (const std::string& key : linear_stage_keys(p)) {
      if (config.has(key)) prefix = p;
    }
    if (prefix != nullptr) break;
  }
  if (prefix == nullptr) {
    std::cerr << "hystloop-identify: --true-stage " << file
              << ": no plant.stage or stage section with a linear stage\n";
    return 2;
  }
  const LinearStageSpec spec = read_linear_stage(config, prefix, LinearStageSpec{});
  const double dt_s = 1.0 / r.sample_rate_Hz;
  const DiscreteLinearStage sampled = discretise(spec, dt_s);
  const bool end_of_tick = !args.continuous && args.sample_at == "end";
  double worst_dB = 0.0, worst_deg = 0.0, worst_dB_Hz = 0.0, worst_deg_Hz = 0.0;
  std::size_t compared = 0, inside = 0;
  for (std::size_t i = 0; i < frf.frequency_Hz.size(); ++i) {
    const double f = frf.frequency_Hz[i];
    if (f > args.compare_to_Hz) continue;
    ++compared;
    const std::complex<double> t = spec.frequency_response(f);  // unit DC gain
    const std::complex<double> m = fit.model_response(f) / fit.dc_gain;
    const double e_dB = std::abs(20.0 * std::log10(std::abs(m) / std::abs(t)));
    const double e_deg = std::abs(std::arg(m / t)) * 180.0 / std::numbers::pi;
    if (e_dB > worst_dB) worst_dB = e_dB, worst_dB_Hz = f;
    if (e_deg > worst_deg) worst_deg = e_deg, worst_deg_Hz = f;
    const std::complex<double> shift = end_of_tick ? std::polar(1.0, -2.0 * std::numbers::pi * f * dt_s) : 1.0;
    if (std::abs(frf.G[i] - sampled.frequency_response(f) * shift * fit.dc_gain) <= 2.0 * frf.sigma_total[i]) ++inside;
  }
  std::printf(
      "against the true stage (%s of %s), up to %.6g Hz: model within %.3g dB (worst at %.6g Hz) and %.3g deg "
      "(at %.6g Hz); the true response inside the measured +-2 sigma band at %zu of %zu lines\n",
      prefix, file.c_str(), args.compare_to_Hz, worst_dB, worst_dB_Hz, worst_deg, worst_deg_Hz, inside, compared);
  return 0;
}

report::PlotResult write_stage_plots(const FrequencyResponse& frf, const StageFitResult& fit,
                                     const std::string& heading, const fs::path& dir, const std::string& gnuplot) {
  report::PlotResult result;
  const double g0 = std::abs(fit.dc_gain) > 0.0 ? std::abs(fit.dc_gain) : 1.0;
  std::vector<C> model;
  for (double f : frf.frequency_Hz) model.push_back(fit.sampled_response(f));
  const std::vector<double> ph = unwrapped_deg(frf.G), phm = unwrapped_deg(model);
  std::ostringstream d;
  d << "# hystloop-identify --model stage: " << heading << "\n"
    << "# magnitudes normalised by the DC gain " << num(fit.dc_gain, 8) << " per V; phases unwrapped [deg];\n"
    << "# measured and model as fitted: through the zero-order hold, y_k at the start of tick k\n"
    << "# f_Hz mag_dB mag_lo_dB mag_hi_dB phase_deg phase_band_deg model_dB model_phase_deg residual_dB "
       "two_sigma_total_dB sigma_noise_dB\n";
  auto db = [&](double a) { return a > 0.0 ? 20.0 * std::log10(a / g0) : std::nan(""); };
  for (std::size_t i = 0; i < frf.frequency_Hz.size(); ++i) {
    const double a = std::abs(frf.G[i]), s = frf.sigma_total[i];
    const double band = a > 2.0 * s ? std::asin(2.0 * s / a) * 180.0 / std::numbers::pi : 180.0;
    d << num(frf.frequency_Hz[i], 10) << ' ' << num(db(a)) << ' ' << num(db(std::max(a - 2.0 * s, 1e-6 * a))) << ' '
      << num(db(a + 2.0 * s)) << ' ' << num(ph[i]) << ' ' << num(band) << ' ' << num(db(std::abs(model[i]))) << ' '
      << num(phm[i]) << ' ' << num(db(std::abs(frf.G[i] - model[i]))) << ' ' << num(db(2.0 * s)) << ' '
      << num(db(frf.sigma_noise[i])) << '\n';
  }
  report::write_text_file(dir / "stage_frf.dat", d.str());
  result.data_files.push_back(dir / "stage_frf.dat");
  std::ostringstream gp;
  gp << "# Re-plot with: cd <this folder> && gnuplot stage_plots.gp\n"
     << "set terminal @TERMINAL@ size 1000,800 noenhanced\nset encoding utf8\nset grid\nset logscale x\n"
     << "set xlabel 'f [Hz]'\n"
     << "\nset output 'stage_bode.png'\nset multiplot layout 2,1 title \"" << heading
     << ": measured response (+-2 sigma_total) and model, / DC gain\"\n"
     << "set ylabel 'magnitude [dB]'\nset key bottom left\n"
     << "plot 'stage_frf.dat' using 1:3:4 with filledcurves lc rgb '#c6dbef' title 'measured +-2 sigma_total', \\\n"
     << "  '' using 1:2 with lines lw 2 lc rgb '#1f77b4' title 'measured', \\\n"
     << "  '' using 1:7 with lines lw 1 lc rgb '#d62728' title 'model " << fit.numerator_order << "/"
     << fit.denominator_order << ", delay " << num(fit.delay_s * 1e6, 4) << " us'\n"
     << "set ylabel 'phase [deg]'\n"
     << "plot 'stage_frf.dat' using 1:($5-$6):($5+$6) with filledcurves lc rgb '#c6dbef' title 'measured +-2 "
        "sigma_total', \\\n"
     << "  '' using 1:5 with lines lw 2 lc rgb '#1f77b4' title 'measured', \\\n"
     << "  '' using 1:8 with lines lw 1 lc rgb '#d62728' title 'model'\n"
     << "unset multiplot\n"
     << "\nset output 'stage_residual.png'\nset title \"" << heading << ": |measured - model| / DC gain, chi2 per line "
     << num(fit.chi2_per_line, 4) << "\"\nset ylabel '[dB]'\nset key top left\n"
     << "plot 'stage_frf.dat' using 1:9 with points pt 7 ps 0.4 lc rgb '#1f77b4' title '|measured - model|', \\\n"
     << "  '' using 1:10 with lines lc rgb '#ff7f0e' title '2 sigma_total', \\\n"
     << "  '' using 1:11 with lines lc rgb '#2ca02c' title 'sigma_noise'\n"
     << "set output\n";
  report::PlotOptions render;
  render.gnuplot = gnuplot;
  report::render_script(
      {"stage_plots.gp", gp.str(), {"stage_bode.png", "stage_residual.png"}, "gnuplot.log", "stage plots", ""}, dir,
      render, result);
  if (result.warning.empty()) fs::remove(dir / "gnuplot.log");
  return result;
}

StageFitOptions fit_options(const IdentifyArgs& args, const StageRecord& r) {
  StageFitOptions o;
  o.unit_dc_gain = false;  // the data carry the actuator's gain: reported, then normalised away
  o.zoh_sample_rate_Hz = args.continuous ? 0.0 : r.sample_rate_Hz;
  o.max_delay_s = args.max_delay_s;
  o.max_order = args.max_order;
  set_stage_order(args.order, o);
  return o;
}

// Where learning goes anyway beside the fitted stage: its lowest lightly damped pole or zero, by the
// compensator's own rule (lowest_linear_feature_hz) on the model this run writes. 0: none.
double lowest_feature_hz(const StageRecord& r, const StageFitResult& fit) {
  StageModel stage;
  stage.kind = StageModel::Kind::kLinear;
  stage.linear = fitted_spec(fit);
  try {
    return lowest_linear_feature_hz(stage, 1.0 / r.sample_rate_Hz);
  } catch (const ParameterError&) {  // a fit the stage model refuses: the compensator refuses it too
    return 0.0;
  }
}
}  // namespace

std::vector<C> roots_hz_once(const std::vector<C>& roots_rad_s) {
  std::vector<C> out;
  for (const C r : roots_rad_s) {
    const C hz = r / (2.0 * std::numbers::pi);
    if (std::abs(hz.imag()) <= 1e-9 * std::abs(hz)) {
      out.emplace_back(hz.real(), 0.0);
    } else if (hz.imag() > 0.0) {
      out.push_back(hz);
    }
  }
  std::sort(out.begin(), out.end(), [](C a, C b) { return std::abs(a) < std::abs(b); });
  return out;
}

int identify_stage(const IdentifyArgs& args, const ExperimentLogOptions& log_options) {
  StageRecord r = args.from_logs ? read_log_record(args, log_options) : read_csv_record(args);
  if (args.transient_periods >= r.periods || r.periods - args.transient_periods < 2) {
    throw ParameterError("transient-periods", "at least 2 of the " + std::to_string(r.periods) +
                                                  " periods must remain after the transient ones");
  }
  if (!args.band.empty()) {
    const auto [lo, hi] = parse_band(args.band);
    MultisineOptions mo;
    mo.sample_rate_Hz = r.sample_rate_Hz;
    mo.period_samples = r.period_samples;
    mo.f_min_Hz = lo;
    mo.f_max_Hz = hi;
    mo.lines = args.odd_lines ? MultisineLines::odd : MultisineLines::all;
    r.lines = multisine_lines(mo);
  } else if (r.lines.empty()) {
    r.lines = excited_lines(r, args.transient_periods);
  }
  if (r.lines.empty()) throw ParameterError("band", "no line excited in the record");
  std::printf("stage record: %s\n", r.source.c_str());
  FrfOptions fo;
  fo.sample_rate_Hz = r.sample_rate_Hz;
  fo.period_samples = r.period_samples;
  fo.periods = r.periods;
  fo.realisations = r.realisations;
  fo.transient_periods = args.transient_periods;
  const bool end_of_tick = !args.continuous && args.sample_at == "end";
  StageIdentification id;
  double dc_gain = 0.0;  // u -> y [m/V]: what the hysteresis model carries
  if (args.hysteresis_plays > 0) {
    HysteresisStageOptions ho;
    ho.operators = args.hysteresis_plays;
    HysteresisStageIdentification h =
        identify_stage_with_hysteresis(r.u, r.y, r.lines, fo, fit_options(args, r), end_of_tick, ho);
    if (h.linear.ok()) dc_gain = h.linear.fit.dc_gain;
    if (h.ok() && h.rounds > 0) {
      const std::string later = h.not_kept.empty() ? std::string() : " (then " + h.not_kept + ": not kept)";
      std::printf(
          "through the hysteresis: %zu plays fitted with the stage (%d rounds%s); the record's residual %.3g (u -> y "
          "alone: %.3g); the response below is from the hysteresis' output to y\n",
          args.hysteresis_plays, h.rounds, later.c_str(), h.residual_rms, h.residual_rms_linear);
    } else if (h.linear.ok()) {
      const std::string why = !h.stage.ok()         ? h.stage.reason()
                              : !h.not_kept.empty() ? h.not_kept
                                                    : std::string("the plays explained nothing");
      std::printf("through the hysteresis: no fit (%s); the stage from u -> y alone\n", why.c_str());
    }
    id = h.ok() && h.rounds > 0 ? std::move(h.stage) : std::move(h.linear);
  } else {
    id = identify_stage_dynamics(r.u, r.y, r.lines, fo, fit_options(args, r), end_of_tick);
    dc_gain = id.fit.dc_gain;
  }
  if (!id.ok()) {
    std::cerr << "hystloop-identify: " << id.reason() << "\n";
    return kExitFailure;
  }
  const FrequencyResponse& frf = id.frf;
  const StageFitResult& fit = id.fit;
  print_fit(frf, fit, dc_gain);
  const double known_to_hz = model_known_to_hz(id, kLearningShareOfResonance * lowest_feature_hz(r, fit));
  std::printf("model known (within %g %% of the record, +2 sigma) up to %.6g Hz\n", 100.0 * kStageKnownWithin,
              known_to_hz);
  const FittedServo servo = fitted_servo(r, fit);
  print_servo(servo);
  std::string heading = fs::path(args.files.front()).filename().string();
  const OutputTarget target = output_target(args.out);
  if (const int rc = write_yaml(target, stage_yaml(r, frf, fit, dc_gain, heading, known_to_hz, servo)); rc != 0) {
    return rc;
  }
  if (target.plots_dir) {
    const report::PlotResult plots = write_stage_plots(frf, fit, heading, *target.plots_dir, args.gnuplot);
    for (const auto& f : plots.images) std::printf("plot: %s\n", f.string().c_str());
    if (!plots.warning.empty()) std::printf("plots: %s\n", plots.warning.c_str());
  }
  // After the model and plots are written: a comparison that cannot be made loses no fit.
  if (!args.true_stage.empty()) return compare_with_true_stage(r, frf, fit, args);
  return 0;
}

}  // namespace hystloop
