#include "plots.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace hystloop::report {

namespace {

std::ofstream open_for_writing(const std::filesystem::path& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path.string() + ": cannot write");
  return out;
}

void close_checked(std::ofstream& out, const std::filesystem::path& path) {
  out.close();
  if (!out) throw std::runtime_error(path.string() + ": write failed");
}

std::string num(double v) {
  if (!std::isfinite(v)) return "NaN";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

// Runs `gnuplot args...` with `dir` as working directory, output silenced; returns its exit status.
// gnuplot's own messages go to `log_name` in dir.
int run_in(const std::filesystem::path& dir, const std::filesystem::path& exe, const std::vector<std::string>& args,
           const char* log_name = "/dev/null") {
  const pid_t pid = ::fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    if (::chdir(dir.c_str()) != 0) ::_exit(126);
    if (std::freopen("/dev/null", "w", stdout) == nullptr) ::_exit(126);
    if (std::freopen(log_name, "w", stderr) == nullptr) ::_exit(126);
    std::vector<char*> argv;
    std::string program = exe.string();
    argv.push_back(program.data());
    std::vector<std::string> copy = args;
    for (auto& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(program.c_str(), argv.data());
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

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

}  // namespace

namespace {
// convergence.png: the published parameters over time (c1 and the held-out RMS of each
// set; a model change labelled with its model) above the per-second tracking RMS, with every swap
// (the second in which the version the compensator applies changed) marked by a vertical line.
std::string convergence_plot(const ReportMetrics& m) {
  std::ostringstream gp;
  gp << "\nset output 'convergence.png'\nset multiplot layout 2,1 title 'Re-identification: parameters and "
        "tracking error (dashed: a swap at the compensator)'\n";
  std::int32_t version = m.per_second.front().params_version;
  int arrow = 0;
  std::ostringstream arrows;
  for (const auto& bin : m.per_second) {
    if (bin.params_version != version) {
      arrows << "set arrow " << ++arrow << " from " << num(bin.t_s) << ", graph 0 to " << num(bin.t_s)
             << ", graph 1 nohead dt 2 lc rgb 'red'\n";
      version = bin.params_version;
    }
  }
  for (const auto& p : m.params_history) {
    if (p.model_change) gp << "set label '" << p.model << "' at " << num(p.t_s) << ", graph 0.9\n";
  }
  gp << arrows.str() << "set xlabel 't [s]'\nset ylabel 'c1 [nm/V]'\nset y2label 'held-out RMS [nm]'\n"
     << "set y2tics\nset ytics nomirror\n"
     << "plot 'params.dat' using 1:($8 == 1 ? $3 : NaN) with linespoints pt 7 title 'c1 (MEM sets)', "
     << "'params.dat' using 1:($8 == 1 ? $7 : NaN) axes x1y2 with points pt 5 title 'held-out RMS of the set'\n"
     << "unset label\nunset y2tics\nunset y2label\nset ytics mirror\nset ylabel 'RMS error [nm]'\n"
     << "plot 'per_second.dat' using ($1+0.5):2 with linespoints lw 2 pt 7 title 'RMS per second'\n"
     << "unset arrow\nunset multiplot\n";
  return gp.str();
}
}  // namespace

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

PlotResult write_plots(const std::vector<TrackPoint>& ticks, const ReportMetrics& m, const std::filesystem::path& dir,
                       const PlotOptions& options) {
  PlotResult result;
  const bool have_ticks = !ticks.empty();
  const bool have_tracking = m.tracking_samples > 0;
  const bool have_run_ahead = !m.run_ahead_ticks.empty();

  {  // track.dat: every n-th tick.
    const auto path = dir / "track.dat";
    auto out = open_for_writing(path);
    out << "# t_s u_V y_um y_ref_um e_nm   (e = y_ref - y; NaN: no reference for the tick)\n";
    const std::size_t step = std::max<std::size_t>(
        1, (ticks.size() + options.max_points - 1) / std::max<std::size_t>(options.max_points, 1));
    for (std::size_t i = 0; i < ticks.size(); i += step) {
      const auto& p = ticks[i];
      out << num(p.t_s) << ' ' << num(p.u_V) << ' ' << num(p.y_m * 1e6) << ' ' << num(p.y_ref_m * 1e6) << ' '
          << num((p.y_ref_m - p.y_m) * 1e9) << '\n';
    }
    close_checked(out, path);
    result.data_files.push_back(path);
  }
  {
    const auto path = dir / "per_second.dat";
    auto out = open_for_writing(path);
    out << "# t_s rms_error_nm params_version   (t_s = start of the second)\n";
    for (const auto& bin : m.per_second) {
      out << num(bin.t_s) << ' ' << num(bin.rms_error_m ? *bin.rms_error_m * 1e9 : std::nan("")) << ' '
          << bin.params_version << '\n';
    }
    close_checked(out, path);
    result.data_files.push_back(path);
  }
  if (!m.params_history.empty()) {
    const auto path = dir / "params.dat";
    auto out = open_for_writing(path);
    out << "# t_s version c1_nm_per_V c2 c3 residual_nm heldout_rms_nm valid model_change model   (one published "
           "set per row; c1..c3 NaN unless the model is MEM)\n";
    for (const auto& p : m.params_history) {
      out << num(p.t_s) << ' ' << p.version << ' ' << num(p.c1 * 1e9) << ' ' << num(p.c2) << ' ' << num(p.c3) << ' '
          << num(p.residual_m * 1e9) << ' ' << num(p.heldout_rms_m * 1e9) << ' ' << (p.valid ? 1 : 0) << ' '
          << (p.model_change ? 1 : 0) << ' ' << p.model << '\n';
    }
    close_checked(out, path);
    result.data_files.push_back(path);
  }
  const Histogram hist = run_ahead_histogram(m);
  {
    const auto path = dir / "run_ahead_hist.dat";
    auto out = open_for_writing(path);
    out << "# bin_low_ticks bin_high_ticks count   (run-ahead margin of each command block: seq - sample_seq)\n";
    for (std::size_t i = 0; i < hist.counts.size(); ++i) {
      const double lo = hist.lo - 0.5 + hist.width * static_cast<double>(i);  // edges between whole ticks
      out << num(lo) << ' ' << num(lo + hist.width) << ' ' << hist.counts[i] << '\n';
    }
    close_checked(out, path);
    result.data_files.push_back(path);
  }

  std::vector<std::string> images;
  std::ostringstream gp;
  gp << "# Re-plot with: cd <this folder> && gnuplot plots.gp   (terminal: edit the first line)\n"
     << "set terminal @TERMINAL@ size 1000,700 noenhanced\n"
     << "set grid\nset key top left\n";
  if (have_ticks) {
    images.push_back("hysteresis_u_y.png");
    gp << "\nset output 'hysteresis_u_y.png'\nset title 'Hysteresis loop: applied voltage u -> measured position y'\n"
       << "set xlabel 'u [V]'\nset ylabel 'y [um]'\n"
       << "plot 'track.dat' using 2:3 with lines lw 1 title 'y(u)'\n";
  }
  if (have_tracking) {
    images.push_back("hysteresis_yref_y.png");
    gp << "\nset output 'hysteresis_yref_y.png'\n"
       << "set title 'Reference y_ref -> measured position y (cf. the MEM paper, Fig. 11)'\n"
       << "set xlabel 'y_ref [um]'\nset ylabel 'y [um]'\nset size ratio -1\n"
       << "plot 'track.dat' using 4:3 with lines lw 1 title 'y(y_ref)', x with lines dt 2 lc rgb 'gray' title 'y = "
          "y_ref'\n"
       << "set size noratio\n";
    images.push_back("tracking_error.png");
    gp << "\nset output 'tracking_error.png'\nset title 'Tracking error e = y_ref - y'\n"
       << "set xlabel 't [s]'\nset ylabel 'e [nm]'\n"
       << "plot 'track.dat' using 1:5 with lines lw 1 title 'e', "
       << "'per_second.dat' using ($1+0.5):2 with linespoints lw 2 pt 7 title 'RMS per second'\n";
  }
  if (!m.params_history.empty() && !m.per_second.empty()) {
    images.push_back("convergence.png");
    gp << convergence_plot(m);
  }
  if (have_run_ahead) {
    images.push_back("run_ahead_histogram.png");
    gp << "\nset output 'run_ahead_histogram.png'\n"
       << "set title 'Run-ahead margin of the command blocks (seq - sample_seq), n = " << m.run_ahead_ticks.size()
       << "'\nset xlabel 'margin [ticks]'\nset ylabel 'command blocks'\nset style fill solid 0.6\n"
       << "set boxwidth 0.9 relative\n"
       << "plot 'run_ahead_hist.dat' using ($1+($2-$1)/2):3 with boxes title 'count'\n";
  }
  gp << "\nunset output\n";

  result.script = dir / "plots.gp";
  auto write_script = [&](const std::string& terminal) {
    std::string text = gp.str();
    text.replace(text.find("@TERMINAL@"), 10, terminal);
    auto out = open_for_writing(result.script);
    out << text;
    close_checked(out, result.script);
  };
  write_script("pngcairo");

  const auto exe = find_executable(options.gnuplot);
  if (exe.empty()) {
    result.warning =
        "gnuplot not found ('" + options.gnuplot + "'): plots skipped (data and plots.gp are in " + dir.string() + ")";
    return result;
  }
  if (images.empty()) {
    result.warning = "no data to plot";
    return result;
  }
  for (const std::string terminal : {"pngcairo", "png"}) {
    if (run_in(dir, exe, {"-e", "set terminal " + terminal}) != 0) continue;  // terminal not built in
    write_script(terminal);
    for (const auto& image : images) std::filesystem::remove(dir / image);
    const int rc = run_in(dir, exe, {"plots.gp"}, "gnuplot.log");
    result.terminal = terminal;
    for (const auto& image : images) {
      if (std::filesystem::exists(dir / image)) result.images.push_back(dir / image);
    }
    if (rc != 0 || result.images.size() != images.size()) {
      result.warning = "gnuplot failed (exit " + std::to_string(rc) + "): " + std::to_string(result.images.size()) +
                       " of " + std::to_string(images.size()) + " plots written; see " + (dir / "gnuplot.log").string();
    }
    return result;
  }
  result.warning = "gnuplot has neither the pngcairo nor the png terminal: plots skipped";
  return result;
}

}  // namespace hystloop::report
