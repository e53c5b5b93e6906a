#include "path_report.hpp"

#include <cstdio>

#include "path_log.hpp"
#include "path_output.hpp"
#include "plot_series.hpp"

namespace hystloop::report {

std::vector<PathFigures> compute_path_report(const std::vector<std::filesystem::path>& logs, const RunData& data,
                                             const ChannelNames& channels, const PathReportOptions& o) {
  if (data.channel_counts.count(channels.scan) == 0) return {};
  std::vector<PathFigures> paths =
      decide_paths(read_path_events(logs, channels, o.compensator_process), data.time_zero_utime());
  const std::vector<LoopWindow> windows = read_windows(paths);
  if (windows.empty()) return paths;
  const std::vector<PathTick> ticks = read_path_ticks(logs, channels, windows);
  for (PathFigures& f : paths) measure_path(f, ticks);
  return paths;
}

void write_path_report(const std::vector<PathFigures>& paths, const ChannelNames& channels,
                       const std::filesystem::path& dir, const PathReportOptions& o) {
  if (paths.empty()) return;
  for (const auto& warning : path_warnings(paths))
    std::fprintf(stderr, "hystloop-report: warning: %s\n", warning.c_str());
  write_text_file(dir / "raster.csv", path_csv(paths));
  PlotResult maps;
  if (!o.no_plots) {
    maps = write_path_maps(paths, dir, o.map, o.plots);
    if (!maps.warning.empty()) std::fprintf(stderr, "hystloop-report: warning: %s\n", maps.warning.c_str());
  }
  if (o.quiet) return;
  std::printf("\nhystloop-report: %zu scan path(s) on %s, r - position per axis\n%s  wrote                  %s",
              paths.size(), channels.scan.c_str(), path_table(paths).c_str(), (dir / "raster.csv").c_str());
  for (const auto& image : maps.images) std::printf(", %s", image.filename().c_str());
  std::printf("\n");
}

}  // namespace hystloop::report
