#include "fit_plots.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/errors.hpp"
#include "plot_series.hpp"  // tools/report: write_text_file

namespace hystloop {
namespace {

namespace fs = std::filesystem;

// 12 digits: a residual of 1e-12 of y stays visible in the file, and y - model can be checked.
std::string num(double v) { return std::isfinite(v) ? number_text(v, 12) : "NaN"; }

std::string model_name(ModelKind kind) { return std::string(to_string(kind)); }

void write_curve(const fs::path& path, const SampleTable& s, const FitCurve& c, std::size_t stride) {
  std::ostringstream out;
  out << "# hystloop-identify: model " << model_name(c.kind) << " over the record, SI units\n";
  if (c.heldout_begin < s.t.size()) {
    out << "# fitted on samples [0, " << c.heldout_begin << "), held out from t = " << num(s.t[c.heldout_begin])
        << " s: RMS " << num(c.heldout_rms_m) << " m after removing the offset " << num(c.offset_m)
        << " m (added to y_model_m here)\n";
  } else {
    out << "# fitted on every sample (nothing held out)\n";
  }
  out << "# residual_m = y_measured_m - y_model_m; heldout = 1: a sample the model was not fitted to\n";
  out << "# t_s u_V y_measured_m y_model_m residual_m heldout\n";
  for (std::size_t k = 0; k < s.t.size(); k += stride) {
    const double model = k < c.y_model_m.size() ? c.y_model_m[k] : std::nan("");
    out << num(s.t[k]) << ' ' << num(s.u[k]) << ' ' << num(s.y[k]) << ' ' << num(model) << ' ' << num(s.y[k] - model)
        << ' ' << (k >= c.heldout_begin ? 1 : 0) << '\n';
  }
  report::write_text_file(path, out.str());
}

std::string curve_file(const FitCurve& c, const char* prefix) { return prefix + model_name(c.kind) + ".dat"; }

std::string heldout_title(const FitCurve& c) {
  if (!std::isfinite(c.heldout_rms_m)) return model_name(c.kind);
  return model_name(c.kind) + ": held-out " + number_text(c.heldout_rms_m * 1e9, 3) + " nm RMS";
}

// A u -> y plot of `file`: measured and model, every sample or only the held-out ones.
std::string loop_plot(const std::string& file, const std::string& model_title, bool heldout_only) {
  const std::string keep = heldout_only ? "($6 == 1 ? $%d * 1e6 : NaN)" : "($%d * 1e6)";
  char measured[64], model[64];
  std::snprintf(measured, sizeof measured, keep.c_str(), 3);
  std::snprintf(model, sizeof model, keep.c_str(), 4);
  return "plot '" + file + "' using 2:" + measured + " with lines lw 2 lc rgb '#1f77b4' title 'measured', \\\n  '" +
         file + "' using 2:" + model + " with lines lw 1 lc rgb '#d62728' title '" + model_title + "'\n";
}

}  // namespace

FitPlotFiles write_fit_plots(const SampleTable& s, const FitPlotInput& in, const fs::path& dir,
                             const FitPlotOptions& options) {
  FitPlotFiles result;
  const std::size_t n = s.t.size();
  const std::size_t stride =
      std::max<std::size_t>(1, (n + options.max_points - 1) / std::max<std::size_t>(1, options.max_points));
  const std::string chosen_file = curve_file(in.chosen, "fit_");
  auto write = [&](const std::string& name, const FitCurve& c) {
    write_curve(dir / name, s, c, stride);
    result.data_files.push_back(dir / name);
  };
  write(chosen_file, in.chosen);
  for (const FitCurve& c : in.candidates) {
    if (curve_file(c, "fit_") != chosen_file) write(curve_file(c, "fit_"), c);
  }
  // The branch held out: the chosen curve's own (auto), or a fit on the first part (one model).
  const FitCurve* held = in.heldout ? &*in.heldout : (in.chosen.heldout_begin < n ? &in.chosen : nullptr);
  const std::string held_file = in.heldout ? curve_file(*in.heldout, "heldout_") : chosen_file;
  if (in.heldout) write(held_file, *in.heldout);

  const std::string chosen_name = model_name(in.chosen.kind);
  std::ostringstream gp;
  gp << "# Re-plot with: cd <this folder> && gnuplot plots.gp   (terminal: edit the first line)\n"
     << "set terminal @TERMINAL@ size 1000,700 noenhanced\n"
     << "set encoding utf8\nset grid\nset key top left\n";
  std::vector<std::string> images;
  images.emplace_back("loop_u_y.png");
  gp << "\nset output 'loop_u_y.png'\n"
     << "set title \"" << in.heading << "\\n"
     << chosen_name << ": measured and model loops over the record\"\n"
     << "set xlabel 'u [V]'\nset ylabel 'y [µm]'\n"
     << loop_plot(chosen_file, "model (" + chosen_name + ")", false);

  images.emplace_back("residual.png");
  gp << "\nset output 'residual.png'\n"
     << "set title \"" << in.heading << "\\n"
     << chosen_name << ": residual measured - model\"\n"
     << "set xlabel 't [s]'\nset ylabel 'measured − model [nm]'\n"
     << "plot '" << chosen_file << "' using 1:($6 == 0 ? $5 * 1e9 : NaN) with lines lc rgb '#1f77b4' title '"
     << chosen_name << ", fitted samples'";
  if (held != nullptr) {
    gp << ", \\\n  '" << held_file << "' using 1:($6 == 1 ? $5 * 1e9 : NaN) with lines lc rgb '#ff7f0e' title '"
       << (in.heldout ? chosen_name + " fitted without the held-out branch: " : std::string()) << "held-out branch'";
  }
  gp << "\n";

  if (held != nullptr) {
    images.emplace_back("heldout_u_y.png");
    gp << "\nset output 'heldout_u_y.png'\n"
       << "set title \"" << in.heading << "\\n"
       << heldout_title(*held) << " (fitted on the record before t = " << number_text(s.t[held->heldout_begin], 3)
       << " s)\"\n"
       << "set xlabel 'u [V]'\nset ylabel 'y [µm]'\n"
       << loop_plot(held_file, "predicted (" + chosen_name + ")", true);
  }

  if (!in.candidates.empty()) {
    images.emplace_back("candidates.png");
    const std::size_t count = in.candidates.size();
    const std::size_t cols = count <= 1 ? 1 : 2;
    const std::size_t rows = (count + cols - 1) / cols;
    gp << "\nset output 'candidates.png'\n"
       << "set terminal @TERMINAL@ size " << 700 * cols << "," << 500 * rows << " noenhanced\n"
       << "set multiplot layout " << rows << "," << cols << " title \"" << in.heading
       << ": every model, fitted on the first part, predicting the held-out branch\"\n"
       << "set xlabel 'u [V]'\nset ylabel 'y [µm]'\n";
    for (const FitCurve& c : in.candidates) {
      gp << "set title '" << heldout_title(c) << "'\n" << loop_plot(curve_file(c, "fit_"), model_name(c.kind), true);
    }
    gp << "unset multiplot\n";
  }
  gp << "set output\n";

  report::PlotOptions render;
  render.gnuplot = options.gnuplot;
  report::render_script({"plots.gp", gp.str(), images, "gnuplot.log", "plots", ""}, dir, render, result);
  if (result.warning.empty()) fs::remove(dir / "gnuplot.log");  // kept only to say why gnuplot failed
  return result;
}

}  // namespace hystloop
