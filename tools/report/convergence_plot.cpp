#include "convergence_plot.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "plot_series.hpp"

namespace hystloop::report {

std::string convergence_script(const ReportMetrics& m) {
  if (m.params_history.empty() || m.per_second.empty()) return "";
  const bool have_mem = std::any_of(m.params_history.begin(), m.params_history.end(), [](const ParamsPoint& p) {
    return p.valid && p.model == "mem" && std::isfinite(p.c1);
  });
  const bool have_heldout = std::any_of(m.params_history.begin(), m.params_history.end(),
                                        [](const ParamsPoint& p) { return p.valid && std::isfinite(p.heldout_rms_m); });
  // One time axis for every panel, so that a swap's line crosses them all at one t.
  double x0 = m.per_second.front().t_s, x1 = m.per_second.back().t_s + 1.0;
  for (const auto& p : m.params_history) x0 = std::min(x0, p.t_s), x1 = std::max(x1, p.t_s);

  std::ostringstream gp;
  // A taller canvas for its panels, and fixed margins: the panels' x axes then line up, and so
  // does each swap's line across them.
  gp << "\nset terminal @TERMINAL@ size 1000,1200 noenhanced\nset output 'convergence.png'\nunset title\n"
     << "set lmargin at screen 0.1\nset rmargin at screen 0.9\nset xrange [" << plot_number(x0) << ":"
     << plot_number(x1) << "]\n";
  int arrow = 0;
  for (const auto& s : m.swaps) {
    gp << "set arrow " << ++arrow << " from " << plot_number(s.t_s) << ", graph 0 to " << plot_number(s.t_s)
       << ", graph 1 nohead dt 2 lc rgb 'red'   # v" << s.from << " -> v" << s.to << " at tick " << s.seq << "\n";
  }
  for (const auto& p : m.params_history) {
    if (p.model_change) gp << "set label '" << p.model << "' at " << plot_number(p.t_s) << ", graph 0.9\n";
  }
  gp << "set multiplot layout " << (have_mem ? 4 : 1)
     << ",1 title 'Re-identification: parameter sets and tracking error (dashed red: a swap at the compensator)'\n"
     << "set xlabel 't [s]'\n"
     << "set key below horizontal  # the series fill their panels' corners: a key inside would hide points\n";
  if (have_mem) {
    gp << "set title 'c1: slope at a reversal" << (have_heldout ? ", and the held-out RMS of each set" : "") << "'\n"
       << "set ylabel 'c1 [nm/V]'\n";
    if (have_heldout) gp << "set y2label 'held-out RMS [nm]'\nset y2tics\nset ytics nomirror\n";
    gp << "plot 'params.dat' using 1:($8 == 1 ? $3 : NaN) with linespoints pt 7 title 'c1 (valid MEM sets)'";
    if (have_heldout) {
      gp << ", 'params.dat' using 1:($8 == 1 ? $7 : NaN) axes x1y2 with points pt 5 title 'held-out RMS of the set'";
    }
    gp << "\nunset y2tics\nunset y2label\nset ytics mirror\n"
       << "set title 'c2: growth of the slope with the distance from the reversal'\n"
       << "set ylabel 'c2 [m/V^(1+c3)]'\nset format y '%.3g'\n"
       << "plot 'params.dat' using 1:($8 == 1 ? $4 : NaN) with linespoints pt 7 title 'c2 (valid MEM sets)'\n"
       << "set format y\nset title 'c3: exponent of that growth'\nset ylabel 'c3 [-]'\n"
       << "plot 'params.dat' using 1:($8 == 1 ? $5 : NaN) with linespoints pt 7 title 'c3 (valid MEM sets)'\n";
  }
  gp << "set title 'Tracking RMS error per second" << (have_mem ? "" : " (no valid MEM set in the log)") << "'\n"
     << "set ylabel 'RMS error [nm]'\n"
     << "plot 'per_second.dat' using ($1+0.5):2 with linespoints lw 2 pt 7 title 'RMS per second'\n"
     << "unset multiplot\nunset title\nunset arrow\nunset label\nset autoscale x\nunset lmargin\nunset rmargin\n"
     << "set key inside top left\n"
     << "set terminal @TERMINAL@ size 1000,700 noenhanced\n";
  return gp.str();
}

}  // namespace hystloop::report
