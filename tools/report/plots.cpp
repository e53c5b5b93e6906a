#include "plots.hpp"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <set>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "convergence_plot.hpp"
#include "core/process.hpp"
#include "model_overlay.hpp"
#include "plot_series.hpp"

namespace hystloop::report {

namespace {

struct Histogram {
  double lo = 0.0;
  double width = 1.0;
  std::vector<std::size_t> counts;
};

// Whole-tick bins from the smallest to the largest run-ahead margin, at most 60 of them.
Histogram run_ahead_histogram(const ReportMetrics& m) {
  Histogram h;
  const auto& v = m.run_ahead_ticks;
  if (v.empty()) return h;
  h.lo = v.front();
  const double span = v.back() - v.front() + 1.0;
  h.width = std::max(1.0, std::ceil(span / 60.0));
  h.counts.assign(static_cast<std::size_t>(std::ceil(span / h.width)), 0);
  for (const double x : v) {
    const auto bin = static_cast<std::size_t>(std::floor((x - h.lo) / h.width));
    ++h.counts[std::min(bin, h.counts.size() - 1)];
  }
  return h;
}

std::string joined(const std::set<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : "/") + n;
  return out;
}

// hysteresis_u_y.png: the measured loop coloured by phase, the MEM model's y for the same u on top.
std::string u_y_script(const std::array<SeriesFile, 3>& u_y, bool with_model) {
  static const char* const kTitle[] = {"identification experiment", "tracking", "safe state / holding"};
  static const char* const kColour[] = {"#1f77b4", "#2ca02c", "#a0a0a0"};
  std::ostringstream gp;
  gp << "\nset output 'hysteresis_u_y.png'\n"
     << "set title 'Hysteresis loop: applied voltage u -> measured position y, by phase"
     << (with_model ? "; dashed: the MEM model for the same u" : "")
     << "'\nset xlabel 'u [V]'\nset ylabel 'y [µm]'\nplot ";
  std::string sep;
  for (std::size_t g = 0; g < u_y.size(); ++g) {
    if (u_y[g].file.empty()) continue;
    gp << sep << "'" << u_y[g].file.filename().string() << "' using 2:3 with lines lw 2 lc rgb '" << kColour[g]
       << "' title 'measured, " << kTitle[g] << "'";
    sep = ", ";
  }
  bool titled = false;
  for (std::size_t g = 0; with_model && g < 2; ++g) {  // the model over the experiment and tracking
    if (u_y[g].file.empty()) continue;
    gp << sep << "'" << u_y[g].file.filename().string() << "' using 2:4 with lines dt 2 lw 1 lc rgb '#ff7f0e' "
       << (titled
               ? "notitle"
               : "title 'MEM model from each reversal (the set in use; over the experiment, the set fitted from it)'");
    titled = true;
  }
  gp << "\n";
  return gp.str();
}

// hysteresis_yref_y.png, as the MEM paper's Fig. 11: y_ref -> y with and without compensation.
std::string yref_y_script(const std::array<SeriesFile, 3>& yref_y) {
  static const char* const kTitle[] = {"without compensation", "with compensation", "compensation unknown"};
  static const char* const kColour[] = {"#d62728", "#1f77b4", "#a0a0a0"};
  const bool without = !yref_y[0].file.empty(), with = !yref_y[1].file.empty();
  std::ostringstream gp;
  gp << "\nset output 'hysteresis_yref_y.png'\nset title 'Reference y_ref -> measured position y ";
  if (without && with) {
    gp << "with and without compensation (cf. the MEM paper, Fig. 11)";
  } else {
    const std::size_t only = with ? 1 : (without ? 0 : 2);
    gp << "(cf. the MEM paper, Fig. 11): only " << kTitle[only] << " (" << joined(yref_y[only].modes)
       << ") in this log";
  }
  gp << "'\nset xlabel 'y_ref [µm]'\nset ylabel 'y [µm]'\nset size ratio -1\nplot ";
  for (std::size_t g = 0; g < yref_y.size(); ++g) {
    if (yref_y[g].file.empty()) continue;
    gp << "'" << yref_y[g].file.filename().string() << "' using 2:3 with lines lw 1 lc rgb '" << kColour[g]
       << "' title '" << kTitle[g] << " (mode " << joined(yref_y[g].modes) << ")', ";
  }
  gp << "x with lines dt 2 lc rgb 'gray' title 'y = y_ref'\nset size noratio\n";
  return gp.str();
}

// Full path of an executable (PATH search unless `name` contains '/'), empty if none.
std::filesystem::path find_executable(const std::string& name) {
  if (name.empty()) return {};
  if (name.find('/') != std::string::npos) return ::access(name.c_str(), X_OK) == 0 ? std::filesystem::path(name) : "";
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path != nullptr ? path : "/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    auto candidate = std::filesystem::path(dir.empty() ? "." : dir) / name;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return {};
}

}  // namespace

PlotResult write_plots(const std::vector<TrackPoint>& ticks, const ReportMetrics& m, const std::filesystem::path& dir,
                       const PlotOptions& options) {
  PlotResult result;
  const std::size_t step = decimation_step(ticks.size(), options.max_points);
  {  // track.dat: every step-th tick.
    DataFile out(dir / "track.dat");
    out.text(
        "# t_s u_V y_µm y_ref_µm e_nm mode params_version   (e = y_ref - y; NaN: no reference for the tick; mode: "
        "command_block_t MODE_*, -1 and version -1: no command logged)\n");
    for (std::size_t i = 0; i < ticks.size(); i += step) {
      const auto& p = ticks[i];
      out.num(p.t_s).num(p.u_V).num(p.y_m * 1e6).num(p.y_ref_m * 1e6).num((p.y_ref_m - p.y_m) * 1e9);
      out.integer(p.mode).integer(p.params_version.value_or(-1));
      out.end_row();
    }
    result.data_files.push_back(out.close());
  }
  {
    DataFile out(dir / "per_second.dat");
    out.text("# t_s rms_error_nm params_version   (t_s = start of the second)\n");
    for (const auto& bin : m.per_second) {
      out.num(bin.t_s).num(bin.rms_error_m ? *bin.rms_error_m * 1e9 : std::nan("")).integer(bin.params_version);
      out.end_row();
    }
    result.data_files.push_back(out.close());
  }
  if (!m.params_history.empty()) {
    DataFile out(dir / "params.dat");
    out.text(
        "# t_s version c1_nm_per_V c2_m_per_V^(1+c3) c3 residual_nm heldout_rms_nm valid model_change model   (one "
        "published set per row; c1..c3 NaN unless the model is MEM)\n");
    for (const auto& p : m.params_history) {
      out.num(p.t_s).integer(p.version).num(p.c1 * 1e9).num(p.c2).num(p.c3).num(p.residual_m * 1e9);
      out.num(p.heldout_rms_m * 1e9).integer(p.valid ? 1 : 0).integer(p.model_change ? 1 : 0);
      out.text(" ").text(p.model).end_row();
    }
    result.data_files.push_back(out.close());
  }
  const Histogram hist = run_ahead_histogram(m);
  {
    DataFile out(dir / "run_ahead_hist.dat");
    out.text("# bin_low_ticks bin_high_ticks count   (run-ahead margin of each command block: seq - sample_seq)\n");
    for (std::size_t i = 0; i < hist.counts.size(); ++i) {
      const double lo = hist.lo - 0.5 + hist.width * static_cast<double>(i);  // edges between whole ticks
      out.num(lo).num(lo + hist.width).integer(static_cast<long long>(hist.counts[i]));
      out.end_row();
    }
    result.data_files.push_back(out.close());
  }
  const std::vector<double> model_y = mem_model_y(ticks, m);
  const auto u_y = write_u_y_series(ticks, model_y, dir, options.max_points);
  const auto yref_y = write_yref_y_series(ticks, dir, options.max_points);
  for (const auto* series : {&u_y, &yref_y}) {
    for (const auto& f : *series) {
      if (!f.file.empty()) result.data_files.push_back(f.file);
    }
  }

  std::vector<std::string> images;
  std::ostringstream gp;
  gp << "# Re-plot with: cd <this folder> && gnuplot plots.gp   (terminal: edit the first line)\n"
     << "set terminal @TERMINAL@ size 1000,700 noenhanced\n"
     << "set encoding utf8\nset grid\nset key top left\n";
  if (!ticks.empty()) {
    images.push_back("hysteresis_u_y.png");
    gp << u_y_script(u_y, !model_y.empty());
  }
  if (m.tracking_samples > 0) {
    images.push_back("hysteresis_yref_y.png");
    gp << yref_y_script(yref_y);
    images.push_back("tracking_error.png");
    gp << "\nset output 'tracking_error.png'\nset title 'Tracking error e = y_ref - y'\n"
       << "set xlabel 't [s]'\nset ylabel 'e [nm]'\n"
       << "plot 'track.dat' using 1:5 with lines lw 1 title 'e', "
       << "'per_second.dat' using ($1+0.5):2 with linespoints lw 2 pt 7 title 'RMS per second'\n";
  }
  if (const std::string convergence = convergence_script(m); !convergence.empty()) {
    images.push_back("convergence.png");
    gp << convergence;
  }
  if (!m.run_ahead_ticks.empty()) {
    images.push_back("run_ahead_histogram.png");
    gp << "\nset output 'run_ahead_histogram.png'\n"
       << "set title 'Run-ahead margin of the command blocks (seq - sample_seq), n = " << m.run_ahead_ticks.size()
       << "'\nset xlabel 'margin [ticks]'\nset ylabel 'command blocks'\nset style fill solid 0.6\n"
       << "set boxwidth 0.9 relative\n"
       << "plot 'run_ahead_hist.dat' using ($1+($2-$1)/2):3 with boxes title 'count'\n";
  }
  gp << "\nunset output\n";

  render_script({"plots.gp", gp.str(), images, "gnuplot.log", "plots", "no data to plot"}, dir, options, result);
  return result;
}

void render_script(const GnuplotScript& script, const std::filesystem::path& dir, const PlotOptions& options,
                   PlotResult& result) {
  result.script = dir / script.name;
  auto write_script = [&](const std::string& terminal) {
    std::string text = script.text;
    for (auto at = text.find("@TERMINAL@"); at != std::string::npos; at = text.find("@TERMINAL@", at)) {
      text.replace(at, 10, terminal);
    }
    write_text_file(result.script, text);
  };
  write_script("pngcairo");

  const auto exe = find_executable(options.gnuplot);
  if (exe.empty()) {
    result.warning = "gnuplot not found ('" + options.gnuplot + "'): " + script.what + " skipped (data and " +
                     script.name + " are in " + dir.string() + ")";
    return;
  }
  const auto& images = script.images;
  if (images.empty()) {
    result.warning = script.nothing;
    return;
  }
  for (const std::string terminal : {"pngcairo", "png"}) {
    if (run_program_in(dir, exe, {"-e", "set terminal " + terminal}) != 0) continue;  // terminal not built in
    write_script(terminal);
    for (const auto& image : images) std::filesystem::remove(dir / image);
    if (options.progress) options.progress("rendering " + std::to_string(images.size()) + " plots with gnuplot");
    const int rc = run_program_in(dir, exe, {script.name}, script.log.c_str());
    result.terminal = terminal;
    for (const auto& image : images) {
      if (std::filesystem::exists(dir / image)) result.images.push_back(dir / image);
    }
    if (rc != 0 || result.images.size() != images.size()) {
      result.warning = "gnuplot failed on " + script.name + " (exit " + std::to_string(rc) +
                       "): " + std::to_string(result.images.size()) + " of " + std::to_string(images.size()) + " " +
                       script.what + " written; see " + (dir / script.log).string();
    }
    return;
  }
  result.warning = "gnuplot has neither the pngcairo nor the png terminal: " + script.what + " skipped";
}

}  // namespace hystloop::report
