#pragma once
// The error map of a raster scan: the tracking error drawn as an image over the scanned area, as
// a microscopist sees it. A row is a line of the raster, a column a bin along the fast axis; each
// cell holds the RMS of the errors of the samples that fell in it.
//
// Only samples on a line's straight part are binned (raster_point(...).on_straight): in the
// corners the fast axis turns and the slow axis steps, before the start and in the settle it
// holds, so their errors belong to no point of the image. A sample's column is taken from where
// the reference puts the fast axis at its time (the planned path, not the measured position, so
// an error moves no sample to another cell), from its low end (centre - width/2), whichever way
// the line runs: column 0 is
// the low end on trace (direction +1, even lines) and retrace (-1, odd lines) alike, so the image
// is the scanned area and not the order the samples came in. Trace and retrace are also summed
// apart: a hysteresis inverse that is off leaves the stage behind the reference one way and ahead
// of it the other, which shows as a difference between the two.
//
// Errors and positions are SI (metres, seconds) here; only what is drawn is in nm and µm.

#include <cstddef>
#include <filesystem>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "loop/scan_path.hpp"
#include "plots.hpp"

namespace hystloop::report {

inline constexpr double kNoError = std::numeric_limits<double>::quiet_NaN();  // an RMS of no sample

struct ErrorMapOptions {
  std::size_t columns = 128;  // bins along the fast axis, [4, 4096]
  // Throws ParameterError naming the field ("error_map.columns").
  void validate() const;
};

struct ErrorCell {
  double rms_m = kNoError;  // RMS of the errors binned here [m]; NaN when none was
  std::size_t samples = 0;  // how many
};

// What the whole map says, over the binned samples only.
struct ErrorMapSummary {
  std::size_t samples = 0;  // binned (on a straight part)
  std::size_t skipped = 0;  // not binned: in a corner, before the start, in the settle or after
  double rms_m = kNoError;  // over every binned sample; NaN when none
  std::size_t trace_samples = 0, retrace_samples = 0;
  double trace_rms_m = kNoError;    // lines run towards centre + width/2 (direction +1); NaN when none
  double retrace_rms_m = kNoError;  // lines run back (direction -1); NaN when none
  // The cell of the largest RMS (the first in row-major order among equals); NaN and 0, 0 when
  // no sample was binned.
  double worst_rms_m = kNoError;
  std::size_t worst_row = 0, worst_column = 0;
  double empty_fraction = 1.0;  // of the rows x columns cells, those without a sample
};

// Rows x columns cells and the summary; made by build_error_map only.
class ErrorMap {
 public:
  std::size_t rows() const noexcept { return rows_; }
  std::size_t columns() const noexcept { return columns_; }
  // Row = the raster's line, column 0 at the fast axis's low end. Throws std::out_of_range.
  ErrorCell cell(std::size_t row, std::size_t column) const;
  // A cell's centre: along the fast axis [m] ...
  double x_m(std::size_t column) const noexcept;
  // ... and on the slow axis [m]: where the reference puts it at the middle of the line (the
  // line's step; the ramp's position there).
  double y_m(std::size_t row) const noexcept;
  int fast_axis() const noexcept { return fast_axis_; }  // the spec's: 0 x, 1 y, 2 z
  int slow_axis() const noexcept { return slow_axis_; }
  // The slow axis's travel [m]: 0 when every line is at the same place.
  double height_m() const noexcept { return height_m_; }
  const ErrorMapSummary& summary() const noexcept { return summary_; }

 private:
  // An empty map (every cell NaN) of spec.lines rows, for a validated spec and column count.
  ErrorMap(const RasterSpec& spec, std::size_t columns);
  friend ErrorMap build_error_map(const RasterSpec&, std::span<const double>, std::span<const double>,
                                  const ErrorMapOptions&);

  std::size_t rows_ = 0, columns_ = 0;
  int fast_axis_ = 0, slow_axis_ = 1;
  double x_low_m_ = 0.0, column_width_m_ = 0.0, height_m_ = 0.0;
  std::vector<double> row_y_m_;
  std::vector<double> sum_sq_m2_;  // row-major
  std::vector<std::size_t> samples_;
  ErrorMapSummary summary_;
};

// Bins error_m[i] (e.g. y_ref - y) of the sample at loop time t_s[i] as described above. Validates
// the spec ("raster.lines", ...) and the options; throws ParameterError for spans of different
// lengths ("error_m") or a value that is not finite ("t_s[17]", "error_m[3]").
ErrorMap build_error_map(const RasterSpec& spec, std::span<const double> t_s, std::span<const double> error_m,
                         const ErrorMapOptions& options);

// Writes DIR/STEM.dat (one row per cell, "x_µm y_µm rms_nm samples", a blank line after every
// line of the raster; NaN for an empty cell, which gnuplot leaves blank) and DIR/STEM.gp, and
// renders DIR/STEM.png with gnuplot as the report's other plots (plots.hpp's render_script): the
// image of the RMS [nm] over x and y [µm] (over the line number when every line is at the same y),
// a colour bar "tracking error RMS [nm]", titled `title` with the overall RMS. No image when no
// sample was binned. Without gnuplot the data and the script are written and the result's warning
// says why the PNG is missing. Throws std::runtime_error if a file cannot be written.
PlotResult write_error_map(const ErrorMap& map, const std::filesystem::path& dir, const std::string& stem,
                           const std::string& title, const PlotOptions& options = {});

}  // namespace hystloop::report
