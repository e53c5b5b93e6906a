#pragma once
// The scan-path table: for each path on HX_SCAN (a raster or a Lissajous figure of every axis) that
// the compensator took, per axis of the stage, the RMS and max of r_a - position over the path,
// and the samples of a raster's error maps (error_map.hpp). No I/O here (path_log.hpp reads the
// log, path_output.hpp writes the results), so each figure can be checked on generated data.
//
// Which paths are measured: those the compensator reports as taken (HX_STATUS: the detail
// "trajectory V taken: scan taken by N axes ...: from loop time A s to B s", V the path's version).
// A path it refused, or whose verdict is not in the log, is listed with why and not measured: a
// refused path never ran, and without the verdict the loop time it started at is unknown. (Every
// scan_t with sensor ticks after it would not do: a refused path, or a repeat, has ticks too.)
//
// The reference r_a(t) is the path's own for axis a (scan_path.hpp's evaluate at the loop time
// t = seq * dt): what the compensator sends as the axis's y_ref (the decoupled share of C^-1 r
// goes into the feedforward only). Two things the log does not state exactly are found from the
// logged y_ref:
//   - the start: the verdict prints it to 0.1 ms, and half a tick off is ~2.5 nm of reference on a
//     1 µm line at 50 lines/s; it is refined by least squares of every axis's logged y_ref against
//     the path (Gauss-Newton on the start alone, from the printed value);
//   - a raster's corner_s sent as 0 (the compensator's choice: two periods of its stage model's
//     resonance, a model the log does not hold): from the fast axis's speed in the middle of the
//     lines, v = width / (1/L - c + 2c/pi) (trajectory.hpp's rounded triangle, L the line rate).
// max |y_ref_a - r_a| over the measured ticks (reference_mismatch_m) then says whether the path
// was found exactly (~1e-20 m when it was).
//
// Measured ticks: loop time in [start, start + lines / line_rate) for a raster (its lines with
// their corners, not the settle after them), [start, start + duration) for a Lissajous figure,
// received before the first compensator report naming another trajectory_version (a newer
// trajectory or path took over: interrupted), not in the safe state. Position: the simulated
// stage's true position (HX_SIM_TRUTH) when the log has it for the path's ticks (a tick without it
// is then left out and counted missing), else the measured y_m.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "path_log.hpp"

namespace hystloop::report {

enum class PathVerdict : std::uint8_t { kTaken, kRefused, kNone };
const char* to_string(PathVerdict verdict) noexcept;

enum class PositionSource : std::uint8_t { kTrue, kMeasured };
const char* to_string(PositionSource source) noexcept;  // "true (HX_SIM_TRUTH)", "measured (y_m)"

struct PathAxisFigures {
  int axis = 0;
  std::string role;                            // raster: "fast", "slow", "holds"; Lissajous: "moves", "holds"
  std::size_t ticks = 0;                       // measured
  std::optional<double> rms_m, max_abs_m;      // of r_a - position
  std::size_t reference_ticks = 0;             // of them with a logged y_ref
  std::optional<double> reference_mismatch_m;  // max |y_ref - r_a| over those
};

struct PathFigures {
  LoggedPath path;      // with start_s, and a raster's corner_s, as found (above)
  double sent_s = 0.0;  // report time of its receipt
  PathVerdict verdict = PathVerdict::kNone;
  std::string verdict_text;                    // the compensator's words
  std::string skipped;                         // why it was not measured; empty when it was
  std::optional<double> printed_start_s;       // the start the verdict printed [s of loop time]
  std::optional<std::int64_t> replaced_utime;  // the report naming another trajectory_version
  std::string corner_source;                   // raster: "sent" or "from the reference (...)"
  double from_s = 0.0, to_s = 0.0;             // the measured loop time [from, to)
  bool interrupted = false;                    // another trajectory took over before the end
  PositionSource position = PositionSource::kMeasured;
  std::size_t expected_ticks = 0;  // ticks in [from, to)
  std::size_t missing_ticks = 0;   // of them not in the log (against the true position: or without one)
  std::size_t safe_ticks = 0;      // of them in the safe state
  int axes = 0;                    // of the sensor blocks
  std::vector<PathAxisFigures> per_axis;
  // Every measured tick: its loop time and, per axis, r_a - position (the error maps' samples).
  std::vector<double> t_s;
  std::array<std::vector<double>, kScanAxes> error_m;

  const RasterSpec* raster() const noexcept { return std::get_if<RasterSpec>(&path.path); }
  bool measured() const noexcept { return skipped.empty(); }
  // "raster v7: 64 lines of 1 µm x 1 µm at 50 lines/s (x fast, y slow, steps, decoupled)",
  // "Lissajous v8: x 0.25 µm 40 Hz, y 0.25 µm 38 Hz, 1 s (decoupled)"
  std::string label() const;
};

// Each path's verdict, the start it printed and whether it was replaced (nothing measured yet).
std::vector<PathFigures> decide_paths(const PathEvents& events, std::int64_t time_zero_utime);

// The loop time to read ticks for: around each path that may be measured, with a margin for
// the start's refinement.
std::vector<LoopWindow> read_windows(const std::vector<PathFigures>& paths);

// Measures one taken path on the ticks read (those of other paths and outside its loop time are
// ignored); sets `skipped` when it cannot.
void measure_path(PathFigures& figures, std::span<const PathTick> ticks);

// Every axis's reference of a path at loop time t.
AxisPositions path_reference(const LoggedPath& path, double t_s) noexcept;

// A raster's corner from the fast axis's logged y_ref (above), its start known to a fraction of a
// line; nullopt when too few lines have a reference or the speed gives no corner below 0.8 of a line.
std::optional<double> raster_corner_from_reference(const RasterSpec& spec, std::span<const PathTick> ticks);

// The start that best fits every axis's logged y_ref over [start, end) of the path, from the path's
// start_s; nullopt without a tick with a reference that moves.
std::optional<double> fit_start(const LoggedPath& path, std::span<const PathTick> ticks);

}  // namespace hystloop::report
