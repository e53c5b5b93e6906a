// hystloop-report: the figures of a recorded run, from LCM event logs.
//
//   hystloop-report LOG... --out DIR [--axis x|y|z] [--csv CHANNEL]... [--from S] [--to S] [--skip-initial S]
//                   [--rig PREFIX] [--quiet] [--no-plots] [--gnuplot PATH] [--scan | --no-scan] [--scan-settle S]
//                   [--map-columns N]
//
// Writes DIR/summary.json, DIR/<channel>.csv for each --csv, and the plots (PNG via
// gnuplot, with their data files and plots.gp); prints a table of the main figures.
// Every figure, table and plot is of one axis of the stage (--axis, default x): its ticks,
// commands, true positions, parameter sets and trajectories; a log whose sensor blocks lack it is
// refused (exit 2), naming the axes they carry.
// A log of several periodic trajectories (deploy/hystloop scan), or --scan, also gets the scan
// table (scan_report.hpp: scan.json, scan.md, scan_*.png).
// A log with paths on HX_SCAN (hystloop-ctl scan raster|lissajous) gets the scan-path table of
// every axis (path_report.hpp: raster.csv, error_map_<axis>.png, summary.json's scan_paths),
// printed last.
// A file that is empty, holds no event, bytes that are not events (skipped by the reader) or a
// truncated last event is named in a warning on stderr; so are events on the rig's channels
// that do not decode (summary.json: undecodable_events).
// A log of 4 MB or more gets a line on stderr as each phase starts (not with --quiet).
// Exit status: 0 done (a missing gnuplot is a warning), 1 a log could not be read, nothing in
// the logs decoded (no output is written then), or an output could not be written, 2 bad
// arguments.

#include <CLI/CLI.hpp>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "core/cli.hpp"
#include "core/clock.hpp"
#include "core/errors.hpp"
#include "csv_export.hpp"
#include "lcm/channels.hpp"
#include "lcm/rig_auth.hpp"
#include "log_reader.hpp"
#include "models/axis_coupling.hpp"
#include "path_report.hpp"
#include "plot_series.hpp"
#include "plots.hpp"
#include "report_metrics.hpp"
#include "report_table.hpp"
#include "scan_report.hpp"
#include "summary_json.hpp"

namespace {

namespace fs = std::filesystem;
using namespace hystloop;
using namespace hystloop::report;

struct Options {
  std::vector<fs::path> logs;
  fs::path out;
  std::vector<std::string> csv;
  ReportOptions range;  // --from, --to, --skip-initial, --bridge-process, --logger-process
  std::string rig = std::string(kDefaultRigPrefix);
  std::string key_file;  // --key-file: verify signatures, leave out what fails
  bool quiet = false;
  bool no_plots = false;
  PlotOptions plots;
  ScanReportOptions scan;  // --scan, --no-scan, --scan-settle, --compensator-process
  int axis = 0;            // --axis
  std::size_t map_columns = ErrorMapOptions{}.columns;
};

// A line on stderr as each phase of a long log starts (a 30 s run at 10 kHz is some 25 MB and
// takes seconds), so that a slow report is seen working; nothing for a short log or with --quiet.
class Progress {
 public:
  static constexpr std::uintmax_t kLongLogBytes = 4u << 20;

  Progress(const std::vector<fs::path>& logs, bool quiet) {
    for (const auto& log : logs) {
      std::error_code ec;
      const auto size = fs::file_size(log, ec);
      if (!ec) bytes_ += size;
    }
    enabled_ = !quiet && bytes_ >= kLongLogBytes;
  }
  std::uintmax_t bytes() const noexcept { return bytes_; }
  void phase(const std::string& what) const {
    if (!enabled_) return;
    std::fprintf(stderr, "hystloop-report: [%5.1f s] %s\n", monotonic_s() - start_s_, what.c_str());
  }

 private:
  double start_s_ = monotonic_s();
  std::uintmax_t bytes_ = 0;
  bool enabled_ = false;
};

int run(const Options& o) {
  const ChannelNames channels(o.rig);
  o.range.validate();
  o.scan.figures.validate();
  if (o.plots.max_points == 0) throw ParameterError("--plot-max-points", "must be > 0 (got 0)");

  const Progress progress(o.logs, o.quiet);
  char what[96];
  std::snprintf(what, sizeof what, "reading %zu log file(s), %.1f MB", o.logs.size(),
                static_cast<double>(progress.bytes()) * 1e-6);
  progress.phase(what);
  // Every reader of the log below (figures, scans, paths, CSV) verifies with it.
  if (!o.key_file.empty()) set_process_rig_auth(rig_auth_from_key_file(o.key_file, "--key-file"));
  const RunData data = read_logs(o.logs, channels, o.axis);
  for (const auto& problem : describe_scan_problems(data.files)) {
    std::fprintf(stderr, "hystloop-report: warning: %s\n", problem.c_str());
  }
  if (data.undecodable > 0) {
    std::fprintf(stderr,
                 "hystloop-report: warning: %llu event(s) on the rig's channels did not decode or broke the "
                 "message contract; they are left out\n",
                 static_cast<unsigned long long>(data.undecodable));
  }
  if (data.events == data.undecodable) {
    std::fprintf(stderr, "hystloop-report: nothing decodable in %zu log file(s): no report written\n", o.logs.size());
    return 1;
  }
  require_axis(data, channels.sensor);
  if (data.blocks_without_axis > 0) {
    std::fprintf(stderr, "hystloop-report: warning: %llu %s block(s) do not carry %s; their ticks are left out\n",
                 static_cast<unsigned long long>(data.blocks_without_axis), channels.sensor.c_str(),
                 std::string(axis_name(o.axis)).c_str());
  }
  std::vector<std::string> csv_channels;
  for (const auto& name : o.csv)
    csv_channels.push_back(resolve_channel(name, data.channel_counts, channels.prefix, "--csv"));

  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (ec || !fs::is_directory(o.out)) throw std::runtime_error(o.out.string() + ": cannot create the folder");

  progress.phase("computing the figures of " + std::to_string(data.samples.size()) + " ticks");
  const ReportMetrics metrics = compute_metrics(data, o.range);
  if (data.samples.empty()) {
    std::fprintf(stderr, "hystloop-report: warning: no %s ticks in the log; most figures are null\n",
                 channels.sensor.c_str());
  }
  PathReportOptions path_options;
  path_options.compensator_process = o.scan.compensator_process;
  path_options.map.columns = o.map_columns;
  path_options.quiet = o.quiet;
  path_options.no_plots = o.no_plots;
  path_options.plots = o.plots;
  if (data.channel_counts.count(channels.scan) != 0) progress.phase("measuring the paths on " + channels.scan);
  const std::vector<PathFigures> paths = compute_path_report(o.logs, data, channels, path_options);
  write_text_file(o.out / "summary.json", summary_json(metrics, o.range, o.logs, paths));

  std::vector<CsvExport> exports;
  if (!csv_channels.empty()) {
    progress.phase("exporting CSV");
    exports =
        export_csv(o.logs, csv_channels, data.time_zero_utime(), o.range.lower_s(), o.range.upper_s(), o.out, o.axis);
  }
  PlotResult plots;
  if (!o.no_plots) {
    progress.phase("writing the plots' data");
    PlotOptions plot_options = o.plots;
    plot_options.progress = [&progress](const std::string& step) { progress.phase(step); };
    plots = write_plots(track_points(data, o.range), metrics, o.out, plot_options);
    if (!plots.warning.empty()) std::fprintf(stderr, "hystloop-report: warning: %s\n", plots.warning.c_str());
  }

  if (!o.quiet) {
    std::printf("hystloop-report: %zu log file(s), rig %s\n%s", o.logs.size(), channels.prefix.c_str(),
                format_table(metrics).c_str());
    std::printf("  wrote                  %s", (o.out / "summary.json").c_str());
    for (const auto& e : exports) std::printf(", %s (%zu rows)", e.file.filename().c_str(), e.rows);
    for (const auto& image : plots.images) std::printf(", %s", image.filename().c_str());
    std::printf("\n");
  }
  ScanReportOptions scan = o.scan;
  scan.quiet = o.quiet;
  scan.no_plots = o.no_plots;
  scan.plots = o.plots;
  scan.axis = o.axis;
  progress.phase("looking for a scan (periodic trajectories)");
  const int rc = write_scan_report(o.logs, data, channels, o.out, scan);
  if (!paths.empty()) progress.phase("writing the scan paths' table and error maps");
  write_path_report(paths, channels, o.out, path_options);
  progress.phase("done");
  return rc;
}

int report_main(int argc, char** argv) {
  Options o;
  CLI::App app{
      "hystloop-report: tracking error, late ticks, buffer depth, run-ahead margin, watchdog trips, CPU, message "
      "rates, parameter history and plots of a recorded run, from LCM event logs (times are the log's receive "
      "timestamps, relative to the first sensor tick)"};
  app.add_option("logs", o.logs, "LCM event log file(s); rotated files in recording order")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--out", o.out, "Output folder (created if missing)")->required();
  add_axis_option(&app, "--axis", o.axis,
                  "The axis of a stage of several whose ticks, commands, parameter sets and trajectories every figure, "
                  "table and plot shows (default x; a log whose sensor blocks lack it is refused)");
  app.add_option("--csv", o.csv, "Export a channel to DIR/<channel>.csv, e.g. HX_SENSOR or SENSOR (repeatable)");
  app.add_option("--from", o.range.from_s, "Start of the analysed range [s after the first sensor tick]");
  app.add_option("--to", o.range.to_s, "End of the analysed range [s after the first sensor tick]");
  app.add_option("--skip-initial", o.range.skip_initial_s, "Exclude this warm-up at the start of the range [s]")
      ->capture_default_str();
  app.add_option("--rig", o.rig, "Channel prefix of the rig")->capture_default_str();
  app.add_option("--key-file", o.key_file,
                 "The rig key (auth.key_file of the services): verify the signed channels' messages and leave out "
                 "(and count) those whose signature fails, as the rig refused them");
  app.add_option("--bridge-process", o.range.bridge_process, "Process name of the bridge in HX_STATUS")
      ->capture_default_str();
  app.add_option("--logger-process", o.range.logger_process, "Process name of the logger in HX_STATUS")
      ->capture_default_str();
  app.add_flag("--quiet", o.quiet, "Print nothing but warnings and errors");
  app.add_flag("--no-plots", o.no_plots, "Write no plots");
  app.add_option("--gnuplot", o.plots.gnuplot, "gnuplot executable")->capture_default_str();
  app.add_option("--plot-max-points", o.plots.max_points, "Decimate the plotted ticks to at most this many")
      ->capture_default_str();
  auto* scan = app.add_flag("--scan", o.scan.force,
                            "Write the scan table (scan.json, scan.md, scan_*.png: per periodic trajectory, learning "
                            "off and on) even for a single periodic trajectory; the whole log, whatever --from/--to");
  app.add_flag("--no-scan", o.scan.off, "Do not write the scan table (written by default for 2+ periodic trajectories)")
      ->excludes(scan);
  app.add_option("--scan-settle", o.scan.figures.settle_s,
                 "Scan: skipped at each segment's start, after a trajectory's blend [s]")
      ->capture_default_str();
  app.add_option("--compensator-process", o.scan.compensator_process, "Process name of the compensator in HX_STATUS")
      ->capture_default_str();
  app.add_option("--map-columns", o.map_columns,
                 "Scan paths: bins of a raster's error maps along the fast axis (error_map_<axis>.png)")
      ->check(CLI::Range(4, 4096))
      ->capture_default_str();
  if (const auto exit_code = parse_cli(app, argc, argv)) return *exit_code;
  return run(o);
}

}  // namespace

int main(int argc, char** argv) {
  return hystloop::run_tool("hystloop-report", [&] { return report_main(argc, argv); });
}
