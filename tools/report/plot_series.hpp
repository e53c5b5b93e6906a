#pragma once
// The per-tick data files of the report's plots (plots.hpp), written fast enough for a long log:
// a 30 s run at 10 kHz is 300k ticks, so rows are formatted with std::to_chars into one buffer
// instead of iostreams, and decimated (PlotOptions::max_points) before gnuplot has to draw them.
//
// Ticks are grouped for the loops:
//   u -> y by phase: the identification experiment (command mode EXPERIMENT), tracking (a finite
//     y_ref), the rest (safe state, holding);
//   y_ref -> y by compensation, as the MEM paper's Fig. 11: without (mode off or linear: no
//     hysteresis model in the feedforward), with (mem, pi, katalenic), unknown (no command logged).
// Each group is a file of its own; a group's segments are separated by a blank line so gnuplot
// does not join the end of one to the start of the next.

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "report_metrics.hpp"

namespace hystloop::report {

// A text file written through one buffer. Throws std::runtime_error naming the file when it
// cannot be opened or written.
class DataFile {
 public:
  explicit DataFile(std::filesystem::path path);
  ~DataFile();
  DataFile(const DataFile&) = delete;
  DataFile& operator=(const DataFile&) = delete;

  DataFile& text(std::string_view s);
  DataFile& num(double v);  // "%.9g"-like, NaN for a non-finite value; a space before all but a row's first
  DataFile& integer(long long v);
  void end_row();
  void blank_line();
  const std::filesystem::path& close();  // flushes; throws when a write failed; returns the file's path

 private:
  void flush_if_full();

  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  std::string buffer_;
  bool row_started_ = false;
  bool failed_ = false;
};

// Writes a whole text file (a script, summary.json, scan.md, a legend) as DataFile does.
void write_text_file(const std::filesystem::path& path, std::string_view text);

// A number as the data files and scripts write it ("%.9g"-like; "NaN" when not finite).
std::string plot_number(double v);

// Keep every step-th tick so that at most max_points of n remain (>= 1).
std::size_t decimation_step(std::size_t n, std::size_t max_points) noexcept;

// command_block_t::MODE_* by name ("mem"), "unknown" for anything else.
const char* mode_name(std::int8_t mode) noexcept;

enum class TickPhase : std::uint8_t { kExperiment, kTracking, kOther };
TickPhase phase_of(const TrackPoint& p) noexcept;

enum class Compensation : std::uint8_t { kWithout, kWith, kUnknown };
Compensation compensation_of(std::int8_t mode) noexcept;

// What was written for one group.
struct SeriesFile {
  std::filesystem::path file;   // empty when the group had no tick
  std::size_t rows = 0;         // ticks written (after decimation)
  std::set<std::string> modes;  // command modes of its ticks, by name
};

// DIR/u_y_{experiment,tracking,other}.dat: t_s u_V y_µm y_model_µm (NaN: no model set); indexed
// by TickPhase. `model_y` is mem_model_y (empty: no model column values, all NaN).
std::array<SeriesFile, 3> write_u_y_series(const std::vector<TrackPoint>& ticks, const std::vector<double>& model_y,
                                           const std::filesystem::path& dir, std::size_t max_points);

// DIR/yref_y_{without,with,unknown}.dat: t_s y_ref_µm y_µm, tracking ticks only; indexed by Compensation.
std::array<SeriesFile, 3> write_yref_y_series(const std::vector<TrackPoint>& ticks, const std::filesystem::path& dir,
                                              std::size_t max_points);

}  // namespace hystloop::report
