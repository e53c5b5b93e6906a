// hystloop-identify data.csv --model mem|banning|katalenic|pi|linear|auto [--form integrated|derivative]
//                   [--out params.yaml]
// Exit status: 0 fitted, 1 the data cannot support a fit (the reason is printed), 2 usage or file error.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "ident/banning_fit.hpp"
#include "ident/model_selection.hpp"
#include "ident/params_yaml.hpp"
#include "ident/sample_csv.hpp"

namespace {

using namespace hystloop;

struct Args {
  std::vector<std::string> files;
  std::string model = "auto";
  std::string form = "integrated";
  std::string out;
  double noise_rms_m = 0.0;
  double min_snr = 3.0;
  std::size_t operators = 15;
  int katalenic_degree = 1;
};

int refuse(FitStatus status, const std::string& reason) {
  std::cerr << "hystloop-identify: no fit (" << to_string(status) << "): " << reason << "\n";
  return 1;
}

int emit(const Args& args, const std::string& yaml) {
  std::cout << "--- YAML\n" << yaml;
  if (!args.out.empty()) {
    std::ofstream f(args.out);
    f << "# written by hystloop-identify\n" << yaml;
    if (!f) {
      std::cerr << "hystloop-identify: cannot write " << args.out << "\n";
      return 2;
    }
    std::cout << "written to " << args.out << "\n";
  }
  return 0;
}

int fit_single(const Args& args, const SampleTable& s) {
  if (args.model == "mem") {
    MemFitOptions o;
    o.form = args.form == "derivative" ? MemFitForm::derivative : MemFitForm::integrated;
    o.noise_rms_m = args.noise_rms_m;
    o.min_snr = args.min_snr;
    const MemFitResult r = fit_mem(s.u, s.y, o);
    if (!r.ok()) return refuse(r.status, r.reason);
    std::printf("MEM (%s form): c1 = %.6g m/V, c2 = %.6g m/V^(1+c3), c3 = %.6g\n", args.form.c_str(), r.params.c1,
                r.params.c2, r.params.c3);
    std::printf("fit: residual %.4g nm RMS, noise %.4g nm, %zu samples, %zu branches, %.1f ms\n", r.residual_rms_m * 1e9,
                r.noise_rms_m * 1e9, r.samples_used, r.branches_used, r.solve_time_s * 1e3);
    return emit(args, to_yaml(r.params));
  }
  if (args.model == "pi") {
    PiFitOptions o;
    o.operators = args.operators;
    const PiFitResult r = fit_pi(s.u, s.y, o);
    if (!r.ok()) return refuse(r.status, r.reason);
    std::printf("Prandtl-Ishlinskii: %zu plays, offset %.6g m\n", r.weights.size(), r.offset_m);
    for (std::size_t i = 0; i < r.weights.size(); ++i) std::printf("  r = %8.3f V  w = %.6g m/V\n", r.thresholds_V[i], r.weights[i]);
    std::printf("fit: residual %.4g nm RMS, %zu samples, %.1f ms\n", r.residual_rms_m * 1e9, r.samples_used, r.solve_time_s * 1e3);
    try {
      return emit(args, to_yaml(to_pi_params(r)));
    } catch (const ParameterError& e) {
      return refuse(FitStatus::out_of_range, e.what());
    }
  }
  if (args.model == "katalenic") {
    KatalenicFitOptions o;
    o.output_polynomial_degree = args.katalenic_degree;
    const KatalenicFitResult r = fit_katalenic(s.u, s.y, o);
    if (!r.ok()) return refuse(r.status, r.reason);
    std::printf("Katalenic: k1 = %.6g V, k2 = %.6g 1/V, output gain %.6g m/V\n", r.params.k1, r.params.k2,
                r.params.output_shaping.gain);
    std::printf("fit: residual %.4g nm RMS, %zu samples, %.1f ms\n", r.residual_rms_m * 1e9, r.samples_used, r.solve_time_s * 1e3);
    return emit(args, to_yaml(r.params));
  }
  if (args.model == "linear") {
    const LinearFitResult r = fit_linear(s.u, s.y);
    if (!r.ok()) return refuse(r.status, r.reason);
    std::printf("linear: gain = %.6g m/V, offset = %.6g m\n", r.gain_m_per_V, r.offset_m);
    std::printf("fit: residual %.4g nm RMS, %zu samples\n", r.residual_rms_m * 1e9, r.samples_used);
    return emit(args, to_yaml(to_linear_params(r)));
  }
  // auto
  ModelSelectionOptions o;
  o.mem.form = args.form == "derivative" ? MemFitForm::derivative : MemFitForm::integrated;
  o.mem.noise_rms_m = args.noise_rms_m;
  o.pi.operators = args.operators;
  o.katalenic.output_polynomial_degree = args.katalenic_degree;
  const ModelSelection sel = select_model(s.u, s.y, o);
  std::printf("rank  model       status           train [nm]  held-out [nm]  fit [ms]\n");
  for (std::size_t i = 0; i < sel.ranking.size(); ++i) {
    const auto& r = sel.ranking[i];
    std::printf("%4zu  %-10s  %-15s  %10.4g  %13.4g  %8.1f%s%s\n", i + 1, std::string(to_string(r.kind)).c_str(),
                std::string(to_string(r.status)).c_str(), r.train_rms_m * 1e9, r.holdout_rms_m * 1e9, r.fit_time_s * 1e3,
                r.reason.empty() ? "" : "  ", r.reason.c_str());
  }
  if (!sel.ok()) return refuse(sel.status, sel.reason);
  std::printf("held out from sample %zu of %zu; best: %s\n", sel.split_index, s.u.size(),
              std::string(to_string(sel.ranking.front().kind)).c_str());
  try {
    switch (sel.ranking.front().kind) {
      case ModelKind::mem: return emit(args, to_yaml(sel.mem.params));
      case ModelKind::pi: return emit(args, to_yaml(to_pi_params(sel.pi)));
      case ModelKind::katalenic: return emit(args, to_yaml(sel.katalenic.params));
      case ModelKind::linear: return emit(args, to_yaml(to_linear_params(sel.linear)));
    }
  } catch (const ParameterError& e) {
    return refuse(FitStatus::out_of_range, e.what());
  }
  return 1;
}

int fit_banning_files(const Args& args, const std::vector<SampleTable>& tables) {
  std::vector<SampleTable> groups;
  for (const auto& t : tables) {
    for (auto& g : split_experiments(t)) groups.push_back(std::move(g));
  }
  std::vector<BanningExperimentData> data;
  for (const auto& g : groups) {
    const double fs = sample_rate_Hz(g.t);
    if (!(fs > 0.0)) return refuse(FitStatus::size_mismatch, "an experiment's t does not increase: no sample rate");
    data.push_back({g.u, g.y, fs});
  }
  const BanningFitResult r = fit_banning(data);
  std::printf("experiment  offset [V]  amplitude [V]  frequency [Hz]  kind       feature\n");
  for (std::size_t i = 0; i < r.points.size(); ++i) {
    const auto& p = r.points[i];
    if (!p.used) {
      std::printf("%10zu  skipped: %s\n", i, p.note.c_str());
    } else if (p.magnitude_experiment) {
      std::printf("%10zu  %10.3f  %13.3f  %14.3f  magnitude  h = %.5g\n", i, p.offset_V, p.amplitude_V, p.frequency_Hz, p.magnitude);
    } else {
      std::printf("%10zu  %10.3f  %13.3f  %14.3f  loop       centre %.5g nm, slope %.5g nm/V, area %.5g nm V\n", i,
                  p.offset_V, p.amplitude_V, p.frequency_Hz, p.features.y_centre * 1e9, p.features.slope * 1e9,
                  p.features.area * 1e9);
    }
  }
  if (!r.ok()) return refuse(r.status, r.reason);
  std::printf("Banning: a = %.6g m/V, b = %.6g m/V, alpha = %.6g 1/V\n", r.hysteresis.a, r.hysteresis.b, r.hysteresis.alpha);
  if (r.stage_identified) {
    std::printf("         k = %.6g 1/s^2, c = %.6g 1/s (f_n = %.1f Hz, zeta = %.4f)\n", r.stage.k, r.stage.c,
                r.stage.natural_frequency() / (2.0 * 3.141592653589793), r.stage.damping_ratio());
  } else {
    std::printf("         stage not identified: %s\n", r.reason.c_str());
  }
  std::printf("fit: centre line %.4g nm RMS, slopes %.3g %% RMS, areas %.3g %% RMS, magnitudes %.3g %% RMS, %.1f ms\n",
              r.centre_rms_m * 1e9, r.slope_rel_rms * 100.0, r.area_rel_rms * 100.0, r.magnitude_rel_rms * 100.0,
              r.solve_time_s * 1e3);
  return emit(args, to_yaml(r.hysteresis, r.stage_identified ? &r.stage : nullptr));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Fit a hysteresis model to recorded samples (CSV with a header row t,u,y in s, V, m)."};
  Args args;
  app.add_option("files", args.files, "CSV file(s); for banning one per experiment, or one with an 'experiment' column")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--model", args.model, "mem, banning, katalenic, pi, linear, or auto (fit all, rank on held-out data)")
      ->check(CLI::IsMember({"mem", "banning", "katalenic", "pi", "linear", "auto"}))
      ->capture_default_str();
  app.add_option("--form", args.form, "MEM data form: integrated branches or the paper's derivative")
      ->check(CLI::IsMember({"integrated", "derivative"}))
      ->capture_default_str();
  app.add_option("--out", args.out, "write the YAML config snippet to this file");
  app.add_option("--noise-rms-m", args.noise_rms_m, "sensor noise RMS [m]; 0 = estimate from the data")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--min-snr", args.min_snr, "MEM derivative form: keep points with at least this SNR")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--operators", args.operators, "PI: number of play operators")->check(CLI::Range(1, 32))->capture_default_str();
  app.add_option("--katalenic-degree", args.katalenic_degree, "Katalenic: output shaping polynomial degree (1 = linear)")
      ->check(CLI::Range(1, 7))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    std::vector<SampleTable> tables;
    for (const auto& f : args.files) tables.push_back(read_sample_csv(f));
    if (args.model == "banning") return fit_banning_files(args, tables);
    if (tables.size() != 1) {
      std::cerr << "hystloop-identify: --model " << args.model << " takes one file (got " << tables.size() << ")\n";
      return 2;
    }
    return fit_single(args, tables.front());
  } catch (const CsvError& e) {
    std::cerr << "hystloop-identify: " << e.what() << "\n";
    return 2;
  } catch (const ParameterError& e) {
    std::cerr << "hystloop-identify: " << e.what() << "\n";
    return 2;
  }
}
