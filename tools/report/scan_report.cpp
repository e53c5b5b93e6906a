#include "scan_report.hpp"

#include <cstdio>

#include "plot_series.hpp"
#include "scan_log.hpp"
#include "scan_output.hpp"

namespace hystloop::report {

int write_scan_report(const std::vector<std::filesystem::path>& logs, const RunData& data, const ChannelNames& channels,
                      const std::filesystem::path& dir, const ScanReportOptions& o) {
  if (o.off) return 0;
  const ScanEvents events = read_scan_events(logs, channels, o.compensator_process, o.axis);
  if (!o.force && periodic_trajectories(events) < 2) return 0;
  if (periodic_trajectories(events) == 0) {
    std::fprintf(stderr, "hystloop-report: --scan: no periodic trajectory on %s in the log: no scan table\n",
                 channels.trajectory.c_str());
    return 1;
  }
  const ScanResult scan = compute_scan(data, events, o.figures);
  std::string clamped;  // the segments the bridge clamped in: a line the limits did not hold
  for (const auto& r : scan.references) {
    for (const auto* seg : {&r.off, &r.on}) {
      if (*seg && (*seg)->clamped_ticks > 0) {
        clamped += (clamped.empty() ? "" : ", ") + r.label() + " learning " + to_string((*seg)->learning) + ": " +
                   std::to_string((*seg)->clamped_ticks);
      }
    }
  }
  if (!clamped.empty()) {
    std::fprintf(stderr, "hystloop-report: warning: scan: ticks clamped by the bridge (range or slew): %s\n",
                 clamped.c_str());
  }
  const std::string table = scan_table(scan);
  write_text_file(dir / "scan.json", scan_json(scan, logs));
  std::string md = "# Scan: tracking error per line-rate reference, learning off and on\n\n" + table;
  char rule[160];
  std::snprintf(rule, sizeof rule, "stays within %g x the median of the last %zu", o.figures.converge_factor,
                o.figures.converge_tail);
  md +=
      "\nRMS and max of y_ref - y (measured) after each segment's settling time; RMS true and max true the same "
      "against the simulated stage's true position (HX_SIM_TRUTH; — without it, e.g. on hardware); clamped ticks "
      "(SATURATED or "
      "SLEW_LIMITED) and late ticks over the whole segment; converged after: periods before the first from which "
      "every period's RMS " +
      std::string(rule) + " (scan.json: every figure, the per-period series).\n";
  for (const auto& r : scan.references) {
    if (!r.on || r.on->period_rms_m.empty()) continue;
    md += "\nPer-period RMS with learning on, " + r.label() + " [nm]:";
    for (const double v : r.on->period_rms_m) {
      char buf[24];
      std::snprintf(buf, sizeof buf, " %.3g", v * 1e9);
      md += buf;
    }
    md += "\n";
  }
  write_text_file(dir / "scan.md", md);
  PlotResult plots;
  if (!o.no_plots) {
    plots = write_scan_plots(data, scan, dir, o.plots);
    if (!plots.warning.empty()) std::fprintf(stderr, "hystloop-report: warning: %s\n", plots.warning.c_str());
  }
  if (!o.quiet) {
    const std::string refused = scan.refused() ? ", " + std::to_string(scan.refused()) + " refused" : "";
    std::printf("\nhystloop-report: scan, %zu reference(s)%s\n%s  wrote                  %s, %s",
                scan.references.size(), refused.c_str(), table.c_str(), (dir / "scan.json").c_str(),
                (dir / "scan.md").c_str());
    for (const auto& image : plots.images) std::printf(", %s", image.filename().c_str());
    std::printf("\n");
  }
  return 0;
}

}  // namespace hystloop::report
