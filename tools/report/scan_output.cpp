#include "scan_output.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "plot_series.hpp"

namespace hystloop::report {

namespace {

using Json = nlohmann::ordered_json;  // keys in the order written

Json num(const std::optional<double>& v) { return v && std::isfinite(*v) ? Json(*v) : Json(nullptr); }

Json segment_json(const std::optional<SegmentFigures>& s) {
  if (!s) return nullptr;
  Json periods = Json::array();
  for (const double r : s->period_rms_m) periods.push_back(r);
  return Json{{"learning", to_string(s->learning)},
              {"start_s", s->start_s},
              {"end_s", s->end_s},
              {"analysed_from_s", s->analysed_from_s},
              {"ticks", s->ticks},
              {"analysed_ticks", s->analysed_ticks},
              {"rms_error_m", num(s->rms_m)},
              {"max_abs_error_m", num(s->max_abs_m)},
              {"rms_error_last_s_m", num(s->rms_last_m)},
              {"true_position_ticks", s->true_ticks},
              {"rms_error_true_m", num(s->rms_true_m)},
              {"max_abs_error_true_m", num(s->max_abs_true_m)},
              {"clamped_ticks", s->clamped_ticks},
              {"saturated_ticks", s->saturated_ticks},
              {"slew_limited_ticks", s->slew_limited_ticks},
              {"late_ticks", s->late_ticks},
              {"safe_ticks", s->safe_ticks},
              {"period_ticks", s->period_ticks},
              {"periods", s->period_rms_m.size()},
              {"periods_to_converge", s->periods_to_converge ? Json(*s->periods_to_converge) : Json(nullptr)},
              {"tail_median_rms_m", num(s->tail_median_m)},
              {"period_rms_m", periods},
              {"compensator_learned_rms_m", num(s->learned_rms_m)},
              {"compensator_learning_periods", s->learning_periods ? Json(*s->learning_periods) : Json(nullptr)},
              {"mode", s->mode},
              {"model_switches", s->model_switches},
              {"params_swaps", s->params_swaps}};
}

std::string nm(const std::optional<double>& m, const char* format = "%.2f") {
  if (!m) return "—";
  char buf[32];
  std::snprintf(buf, sizeof buf, format, *m * 1e9);
  return buf;
}

// Markdown cells must not contain '|' or line breaks.
std::string cell(std::string text) {
  for (char& c : text) {
    if (c == '|' || c == '\n') c = '/';
  }
  return text;
}

// One segment's error for the plot: the ticks' min and max per bucket (the envelope survives
// the decimation), time since origin_s (the reference's first segment: off, then on, follow).
void write_error_block(DataFile& out, const RunData& run, const std::optional<SegmentFigures>& s, double origin_s,
                       std::size_t max_points) {
  if (!s) {
    out.text("NaN NaN\n\n\n");  // keeps the block numbering: two blocks per reference
    return;
  }
  std::vector<std::pair<double, double>> ticks;
  for (const auto& k : run.samples) {
    const double t = run.t_s(k.recv_utime);
    if (t < s->start_s || t >= s->end_s || !std::isfinite(k.y_ref_m)) continue;
    ticks.emplace_back(t - origin_s, (k.y_ref_m - k.y_m) * 1e9);
  }
  std::sort(ticks.begin(), ticks.end());
  const std::size_t bucket =
      std::max<std::size_t>(1, (2 * ticks.size() + max_points - 1) / std::max<std::size_t>(max_points, 1));
  for (std::size_t i = 0; i < ticks.size(); i += bucket) {
    const auto end = ticks.begin() + static_cast<std::ptrdiff_t>(std::min(ticks.size(), i + bucket));
    const auto [lo, hi] = std::minmax_element(ticks.begin() + static_cast<std::ptrdiff_t>(i), end,
                                              [](const auto& a, const auto& b) { return a.second < b.second; });
    const auto& first = lo->first <= hi->first ? *lo : *hi;
    const auto& second = lo->first <= hi->first ? *hi : *lo;
    out.num(first.first).num(first.second).end_row();
    if (bucket > 1) out.num(second.first).num(second.second).end_row();
  }
  if (ticks.empty()) out.text("NaN NaN\n");
  out.text("\n\n");
}

}  // namespace

std::string scan_json(const ScanResult& scan, const std::vector<std::filesystem::path>& files) {
  Json refs = Json::array();
  for (const auto& r : scan.references) {
    const ScanTrajectory& t = r.trajectory;
    refs.push_back(Json{{"reference", r.label()},
                        {"shape", t.shape},
                        {"amplitude_m", t.amplitude_m},
                        {"offset_m", t.offset_m},
                        {"frequency_hz", t.frequency_hz},
                        {"blend_s", t.blend_s},
                        {"corner_s_requested", t.corner_s},
                        {"shape_to_feasible", t.shape_to_feasible},
                        {"trajectory_version", t.version},
                        {"sent_s", r.sent_s},
                        {"verdict", to_string(r.verdict)},
                        {"verdict_detail", r.verdict_detail},
                        {"learning_off", segment_json(r.off)},
                        {"learning_on", segment_json(r.on)}});
  }
  Json logs = Json::array();
  for (const auto& f : files) logs.push_back(f.string());
  const ScanOptions& o = scan.options;
  const Json out{{"logs", logs},
                 {"tick_period_s", num(scan.dt_s)},
                 {"settle_s", o.settle_s},
                 {"last_s", o.last_s},
                 {"converge_factor", o.converge_factor},
                 {"converge_tail_periods", o.converge_tail},
                 {"references_refused", scan.refused()},
                 {"references", refs}};
  return out.dump(2) + "\n";
}

std::string scan_table(const ScanResult& scan) {
  std::ostringstream md;
  char last[32];
  std::snprintf(last, sizeof last, "%g", scan.options.last_s);
  md << "| reference | learning | RMS [nm] | RMS last " << last
     << " s [nm] | max [nm] | RMS true [nm] | max true [nm] | clamped ticks | late ticks | periods | converged after | "
        "model | note |\n"
     << "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- | --- |\n";
  for (const auto& r : scan.references) {
    if (r.verdict == Verdict::kRefused) {
      md << "| " << cell(r.label()) << " | — | — | — | — | — | — | — | — | — | — | — | **refused**: "
         << cell(r.verdict_detail.empty() ? "(no reason given)" : r.verdict_detail) << " |\n";
      continue;
    }
    bool first = true;
    for (const auto* s : {&r.off, &r.on}) {
      const char* learning = s == &r.off ? "off" : "on";
      std::string note;
      if (first) {
        if (r.verdict == Verdict::kShaped)
          note = "shaped: " + r.verdict_detail;
        else if (r.verdict == Verdict::kUnconfirmed)
          note = "unconfirmed: " + r.verdict_detail;
        else
          note = r.verdict_detail;
      }
      first = false;
      if (!*s) {
        md << "| " << cell(r.label()) << " | " << learning << " | — | — | — | — | — | — | — | — | — | — | not measured"
           << (note.empty() ? "" : "; " + cell(note)) << " |\n";
        continue;
      }
      const SegmentFigures& f = **s;
      auto add_note = [&](const std::string& more) { note += (note.empty() ? "" : "; ") + more; };
      if (f.model_switches > 0) add_note("model switched " + std::to_string(f.model_switches) + "x");
      if (f.params_swaps > f.model_switches) {
        add_note(std::to_string(f.params_swaps - f.model_switches) + " parameter swap(s) of the model in use");
      }
      if (f.safe_ticks > 0) add_note(std::to_string(f.safe_ticks) + " ticks in the safe state");
      std::string converged = "—";
      if (f.periods_to_converge) {
        converged = std::to_string(*f.periods_to_converge);
      } else if (f.period_rms_m.size() >= scan.options.converge_tail) {
        converged = "not settled";
      }
      md << "| " << cell(r.label()) << " | " << learning << " | " << nm(f.rms_m) << " | " << nm(f.rms_last_m) << " | "
         << nm(f.max_abs_m, "%.1f") << " | " << nm(f.rms_true_m) << " | " << nm(f.max_abs_true_m, "%.1f") << " | "
         << f.clamped_ticks << " | " << f.late_ticks << " | " << f.period_rms_m.size() << " | " << converged << " | "
         << (f.mode.empty() ? "—" : f.mode) << " | " << cell(note) << " |\n";
    }
  }
  return md.str();
}

PlotResult write_scan_plots(const RunData& run, const ScanResult& scan, const std::filesystem::path& dir,
                            const PlotOptions& options) {
  PlotResult result;
  const std::size_t n = scan.references.size();
  // A panel is ~600 px wide: a few thousand points per curve show the envelope; more only slow
  // gnuplot's cairo lines down (tens of seconds for 10^5 points).
  const std::size_t per_segment =
      std::clamp<std::size_t>(options.max_points / std::max<std::size_t>(1, 2 * n), 200, 6000);
  {
    DataFile out(dir / "scan_error.dat");
    out.text(
        "# t_s e_nm   (t since the reference's first segment; e = y_ref - y; two blocks per reference: learning "
        "off, learning on; min and "
        "max per bucket)\n");
    for (const auto& r : scan.references) {
      const double origin_s = r.off ? r.off->start_s : (r.on ? r.on->start_s : 0.0);
      write_error_block(out, run, r.off, origin_s, per_segment);
      write_error_block(out, run, r.on, origin_s, per_segment);
    }
    result.data_files.push_back(out.close());
  }
  std::map<std::string, std::vector<const ReferenceFigures*>> by_shape;
  for (const auto& r : scan.references) by_shape[r.trajectory.shape].push_back(&r);
  {
    DataFile out(dir / "scan_rates.dat");
    out.text("# frequency_hz rms_last_off_nm rms_last_on_nm rms_off_nm rms_on_nm   (one block per shape)\n");
    for (auto& [shape, refs] : by_shape) {
      out.text("# ").text(shape).text("\n");
      std::sort(refs.begin(), refs.end(),
                [](const auto* a, const auto* b) { return a->trajectory.frequency_hz < b->trajectory.frequency_hz; });
      for (const auto* r : refs) {
        auto v = [](const std::optional<SegmentFigures>& s, bool last_s) {
          const std::optional<double> m = !s ? std::nullopt : (last_s ? s->rms_last_m : s->rms_m);
          return m ? *m * 1e9 : std::nan("");
        };
        out.num(r->trajectory.frequency_hz).num(v(r->off, true)).num(v(r->on, true));
        out.num(v(r->off, false)).num(v(r->on, false)).end_row();
      }
      out.text("\n\n");
    }
    result.data_files.push_back(out.close());
  }
  {
    DataFile out(dir / "scan_periods.dat");
    out.text("# period rms_nm   (learning on; one block per reference)\n");
    for (const auto& r : scan.references) {
      if (r.on && !r.on->period_rms_m.empty()) {
        for (std::size_t i = 0; i < r.on->period_rms_m.size(); ++i) {
          out.integer(static_cast<long long>(i)).num(r.on->period_rms_m[i] * 1e9).end_row();
        }
      } else {
        out.text("NaN NaN\n");
      }
      out.text("\n\n");
    }
    result.data_files.push_back(out.close());
  }

  std::ostringstream gp;
  const std::size_t rows = (n + 1) / 2;
  gp << "# Re-plot with: cd <this folder> && gnuplot scan.gp   (terminal: edit the first line)\n"
     << "set terminal @TERMINAL@ size 1200," << std::max<std::size_t>(400, 300 * rows) << " noenhanced\n"
     << "set grid\nset key top right\n";
  std::vector<std::string> images;
  if (n > 0) {
    images.push_back("scan_error.png");
    gp << "\nset output 'scan_error.png'\nset multiplot layout " << rows << ",2 title 'Tracking error e = y_ref - y "
       << "per reference (the table skips the first " << scan.options.settle_s << " s after a learning request, "
       << "plus the blend after a trajectory)'\n"
       << "set xlabel 't since the reference started, learning off then on [s]'\nset ylabel 'e [nm]'\n"
       << "set key top left opaque\n";
    for (std::size_t i = 0; i < n; ++i) {
      const auto& r = scan.references[i];
      double range = 0.0;
      for (const auto* s : {&r.off, &r.on}) {
        if (*s && (*s)->max_abs_m) range = std::max(range, 1.1 * *(*s)->max_abs_m * 1e9);
      }
      gp << "set title '" << r.label() << (r.verdict == Verdict::kRefused ? " (refused)" : "") << "'\n";
      if (!(range > 0.0)) {  // nothing measured: gnuplot stops on a plot without a valid point
        gp << "set label 1 '" << (r.verdict == Verdict::kRefused ? "refused" : "not measured")
           << "' at graph 0.45, graph 0.6\nplot [0:1] [-1:1] 0 with lines lc rgb 'gray' notitle\nunset label 1\n";
        continue;
      }
      gp << "set yrange [" << plot_number(-range) << ":" << plot_number(range) << "]\n"
         << "plot 'scan_error.dat' index " << 2 * i << " using 1:2 with lines lw 1 lc rgb '#c04040' title "
         << "'learning off', '' index " << 2 * i + 1 << " using 1:2 with lines lw 1 lc rgb '#2060c0' title "
         << "'learning on'\n";
    }
    gp << "unset multiplot\nset yrange [*:*]\n";
  }
  bool any_segment = false, any_periods = false;
  for (const auto& r : scan.references) {
    any_segment = any_segment || r.off || r.on;
    any_periods = any_periods || (r.on && !r.on->period_rms_m.empty());
  }
  if (any_segment) {
    images.push_back("scan_rms_vs_rate.png");
    gp << "\nset terminal @TERMINAL@ size 1000,700 noenhanced\nset output 'scan_rms_vs_rate.png'\n"
       << "set title 'RMS error over the last " << scan.options.last_s << " s of each segment against the line rate'\n"
       << "set logscale xy\nset xlabel 'line rate [Hz]'\nset ylabel 'RMS of y_ref - y [nm]'\nset key top left\n"
       << "plot ";
    std::size_t block = 0;
    for (const auto& [shape, refs] : by_shape) {
      gp << (block ? ", " : "") << "'scan_rates.dat' index " << block << " using 1:2 with linespoints lw 2 pt 7 title '"
         << shape << ", learning off', '' index " << block << " using 1:3 with linespoints lw 2 pt 5 title '" << shape
         << ", learning on'";
      ++block;
    }
    gp << "\nunset logscale\n";
  }
  if (any_periods) {
    images.push_back("scan_periods.png");
    gp << "\nset output 'scan_periods.png'\nset title 'RMS error of each period with learning on'\n"
       << "set logscale y\nset xlabel 'period since the learning request'\nset ylabel 'RMS of y_ref - y [nm]'\n"
       << "set key top right\nplot ";
    bool first = true;
    for (std::size_t i = 0; i < n; ++i) {
      const auto& on = scan.references[i].on;
      if (!on || on->period_rms_m.empty()) continue;
      gp << (first ? "" : ", ") << "'scan_periods.dat' index " << i << " using 1:2 with linespoints pt 7 ps 0.5 title '"
         << scan.references[i].label() << "'";
      first = false;
    }
    gp << "\nunset logscale\n";
  }
  gp << "\nunset output\n";

  render_script({"scan.gp", gp.str(), images, "scan_gnuplot.log", "scan plots", "no reference to plot"}, dir, options,
                result);
  return result;
}

}  // namespace hystloop::report
