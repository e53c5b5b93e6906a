// How well the stage's dynamics are identified through its hysteresis, on plants of the class the
// product is for: the default stage experiment of deploy/hystloop stage (a random-phase multisine
// 5 Hz - 3 kHz, 0.5 V RMS about 20 V, 24 realisations of 5 periods of 0.2 s, the first period of each
// dropped, sampled at the end of each 10 kHz tick) through each plant's hysteresis, stage and
// 1 nm of sensor noise (five draws); the model fitted (the plant's own order) from u -> y (the best
// linear approximation: identify_stage_dynamics) and with the hysteresis
// (identify_stage_with_hysteresis), each against the true stage up to 3 kHz: the worst magnitude
// [dB] and phase [deg] error, median and largest over the draws, and the residual each leaves of
// the record. Prints a table; exit 1 when a fit fails or the fit with the hysteresis is worse than
// the one from u -> y (median beyond 0.05 dB / 0.3 deg).
//
//   build/release/bench/stage_identification_table [--noise-nm 1] [--realisations 24] [--periods 5] [--plays 15] ...
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <exception>
#include <numbers>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "ident/stage_hysteresis_fit.hpp"
#include "ident/stage_identification.hpp"
#include "loop/simulated_stage.hpp"
#include "models/multisine.hpp"
#include "sim/tracking_experiment.hpp"

namespace {

using namespace hystloop;

struct Plant {
  const char* name;
  LinearStageSpec stage;
  const char* order;
  HysteresisPlantSpec hysteresis{};
};

struct Error {
  double dB = 0.0, dB_Hz = 0.0, deg = 0.0, deg_Hz = 0.0;
};

constexpr int kDraws = 5;  // noise draws per plant

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
double max_of(const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); }

Error against(const LinearStageSpec& truth, const StageFitResult& fit, double to_Hz) {
  Error e;
  for (double f = 5.0; f <= to_Hz + 1e-9; f += 5.0) {
    const std::complex<double> t = truth.frequency_response(f);
    const std::complex<double> m = fit.model_response(f) / fit.dc_gain;
    const double dB = std::abs(20.0 * std::log10(std::abs(m) / std::abs(t)));
    const double deg = std::abs(std::arg(m / t)) * 180.0 / std::numbers::pi;
    if (dB > e.dB) e.dB = dB, e.dB_Hz = f;
    if (deg > e.deg) e.deg = deg, e.deg_Hz = f;
  }
  return e;
}

}  // namespace

namespace {

int run(int argc, char** argv) {
  CLI::App app(
      "The stage experiment of deploy/hystloop stage on six simulated plants; the stage fitted from u -> y and with\n"
      "the hysteresis, each against the true stage up to 3 kHz (five noise draws). Exit 1 when a fit fails or the one\n"
      "with the hysteresis is the worse. The options change the experiment (to see what noise and length cost).");
  MultisineOptions mo;  // deploy/hystloop stage's default experiment
  mo.period_samples = 2000;
  mo.f_min_Hz = 5.0;
  mo.f_max_Hz = 3000.0;
  mo.amplitude_V = 0.5;
  mo.offset_V = 20.0;
  mo.periods = 5;
  mo.realisations = 24;
  mo.seed = 1;
  double noise_nm = 1.0;
  app.add_option("--noise-nm", noise_nm, "sensor noise, RMS [nm]")
      ->check(CLI::Range(0.0, 100.0))
      ->capture_default_str();
  app.add_option("--amplitude", mo.amplitude_V, "multisine RMS [V]")
      ->check(CLI::Range(0.01, 10.0))
      ->capture_default_str();
  app.add_option("--periods", mo.periods, "periods per realisation (the first dropped)")
      ->check(CLI::Range(3, 100))
      ->capture_default_str();
  app.add_option("--realisations", mo.realisations, "realisations")->check(CLI::Range(1, 100))->capture_default_str();
  HysteresisStageOptions ho;
  app.add_option("--plays", ho.operators, "play operators of the hysteresis fitted with the stage")
      ->check(CLI::Range(std::size_t{1}, kPiMaxOperators))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  HysteresisPlantSpec bouc_wen = HysteresisPlantSpec::named("bouc_wen");
  bouc_wen.bouc_wen.d = 7.4e-9;
  bouc_wen.bouc_wen.beta = 0.006;
  bouc_wen.bouc_wen.gamma = 0.002;
  const HysteresisPlantSpec mem = HysteresisPlantSpec::named("mem");
  const LinearStageSpec two_mode = two_mode_experiment().series_stage;
  const std::vector<Plant> plants = {
      {"two modes 780 Hz + 2.4 kHz, 1.5 ticks (the example)", two_mode, "2/4"},
      {"one mode 450 Hz zeta 0.02, 2.5 ticks", LinearStageSpec::sum_of_modes({{450.0, 0.02, 1.0}}, 2.5e-4), "0/2"},
      {"1.1 kHz zeta 0.05, zero at +3 kHz, 1 tick",
       LinearStageSpec::zero_pole({{3000.0, 0.0}}, {{-55.0, 1100.0}}, 1e-4), "1/2"},
      {"three modes 600 Hz / 1.5 kHz / 3.2 kHz, 1.5 ticks",
       LinearStageSpec::sum_of_modes({{600.0, 0.03, 0.7}, {1500.0, 0.02, 0.2}, {3200.0, 0.02, 0.1}}, 1.5e-4), "4/6"},
      {"the two modes behind Bouc-Wen hysteresis", two_mode, "2/4", bouc_wen},
      {"the two modes behind MEM hysteresis", two_mode, "2/4", mem},
  };

  const Multisine m = design_multisine(mo);
  FrfOptions fo;
  fo.period_samples = mo.period_samples;
  fo.periods = mo.periods;
  fo.realisations = mo.realisations;
  fo.transient_periods = 1;

  std::printf(
      "| plant | order | from u -> y: worst dB / deg, median (max) of %d noise draws | with the hysteresis | its "
      "largest "
      "at dB / deg [Hz] | record's residual u -> y / with H [nm] |\n| --- | --- | --- | --- | --- | --- |\n",
      kDraws);
  bool held = true;
  for (const Plant& p : plants) {
    std::vector<double> dB[2], deg[2], dB_Hz, deg_Hz;
    double residual[2] = {0.0, 0.0};
    std::string failed;
    for (int draw = 1; draw <= kDraws && failed.empty(); ++draw) {
      SimulatedStageConfig sc;
      sc.plant = PlantKind::kSeries;
      sc.hysteresis = p.hysteresis;
      sc.linear = p.stage;
      sc.noise_rms_m = noise_nm * 1e-9;
      sc.seed = static_cast<std::uint64_t>(draw);
      SimulatedStage stage(sc);
      double t = 0.0;
      constexpr double kDt = 1e-4;
      for (int k = 0; k < 2000; ++k, t += kDt) stage.step(20.0 * std::min(1.0, k / 1000.0), t, kDt);  // to the offset
      std::vector<double> y(m.u_V.size());
      for (std::size_t k = 0; k < y.size(); ++k, t += kDt) y[k] = stage.step(m.u_V[k], t, kDt);  // end of tick k
      StageFitOptions o;
      o.zoh_sample_rate_Hz = 1e4;
      set_stage_order(p.order, o);
      const HysteresisStageIdentification id = identify_stage_with_hysteresis(m.u_V, y, m.lines, fo, o, true, ho);
      if (!id.linear.ok() || !id.ok()) {
        failed = !id.linear.ok() ? id.linear.reason() : id.stage.reason();
        break;
      }
      for (int i = 0; i < 2; ++i) {
        const Error e = against(p.stage, i == 0 ? id.linear.fit : id.stage.fit, 3000.0);
        dB[i].push_back(e.dB);
        deg[i].push_back(e.deg);
        if (i == 1) dB_Hz.push_back(e.dB_Hz), deg_Hz.push_back(e.deg_Hz);
      }
      residual[0] += id.residual_rms_linear / kDraws;
      residual[1] += id.residual_rms / kDraws;
    }
    if (!failed.empty()) {
      std::printf("| %s | %s | no fit: %s | | |\n", p.name, p.order, failed.c_str());
      held = false;
      continue;
    }
    const auto at_max = [](const std::vector<double>& v, const std::vector<double>& where) {
      return where[static_cast<std::size_t>(std::max_element(v.begin(), v.end()) - v.begin())];
    };
    std::printf("| %s | %s | %.2f (%.2f) / %.2f (%.2f) | %.2f (%.2f) / %.2f (%.2f) | %.0f / %.0f | %.2f / %.2f |\n",
                p.name, p.order, median(dB[0]), max_of(dB[0]), median(deg[0]), max_of(deg[0]), median(dB[1]),
                max_of(dB[1]), median(deg[1]), max_of(deg[1]), at_max(dB[1], dB_Hz), at_max(deg[1], deg_Hz),
                residual[0] * 1e9, residual[1] * 1e9);
    // Through the hysteresis never worse than the best linear approximation by more than 0.05 dB / 0.3 deg.
    held = held && median(dB[1]) <= median(dB[0]) + 0.05 && median(deg[1]) <= median(deg[0]) + 0.3;
  }
  return held ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& err) {  // CLI11 building its options, or a fit's ParameterError
    std::fprintf(stderr, "stage_identification_table: %s\n", err.what());
    return 1;
  }
}
