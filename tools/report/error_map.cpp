#include "error_map.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/errors.hpp"
#include "plot_series.hpp"

namespace hystloop::report {

namespace {

constexpr std::size_t kMinColumns = 4;
constexpr std::size_t kMaxColumns = 4096;

double rms_of(double sum_sq, std::size_t n) noexcept {
  return n == 0 ? kNoError : std::sqrt(sum_sq / static_cast<double>(n));
}

void require_finite_samples(const char* name, std::span<const double> values) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) {
      throw ParameterError(std::string(name) + "[" + std::to_string(i) + "]",
                           "not finite (" + number_text(values[i]) + ")");
    }
  }
}

// A gnuplot single-quoted string: a quote inside is doubled.
std::string quoted(const std::string& text) {
  std::string out = "'";
  for (const char c : text) {
    out += c;
    if (c == '\'') out += '\'';
  }
  return out + "'";
}

std::string nm_text(double v_m) { return number_text(v_m * 1e9, 3) + " nm"; }

}  // namespace

void ErrorMapOptions::validate() const {
  if (columns < kMinColumns || columns > kMaxColumns) {
    throw ParameterError("error_map.columns", "must be in [" + std::to_string(kMinColumns) + ", " +
                                                  std::to_string(kMaxColumns) + "], not " + std::to_string(columns));
  }
}

ErrorMap::ErrorMap(const RasterSpec& spec, std::size_t columns)
    : rows_(static_cast<std::size_t>(std::max(spec.lines, 0))),
      columns_(columns),
      fast_axis_(spec.fast_axis),
      slow_axis_(spec.slow_axis),
      x_low_m_(spec.centre_m[static_cast<std::size_t>(spec.fast_axis)] - 0.5 * spec.width_m),
      column_width_m_(spec.width_m / static_cast<double>(columns)),
      height_m_(spec.height_m),
      row_y_m_(rows_),
      sum_sq_m2_(rows_ * columns_, 0.0),
      samples_(rows_ * columns_, 0) {
  // The slow axis's position from the path itself rather than a formula of its own: a step's
  // place for steps, the ramp's position halfway along the line for a ramp.
  for (std::size_t row = 0; row < rows_; ++row) {
    const double mid_s = spec.start_s + (static_cast<double>(row) + 0.5) / spec.line_rate_hz;
    row_y_m_[row] = evaluate(spec, mid_s)[static_cast<std::size_t>(spec.slow_axis)];
  }
}

ErrorCell ErrorMap::cell(std::size_t row, std::size_t column) const {
  if (row >= rows_ || column >= columns_) {
    throw std::out_of_range("error map cell (" + std::to_string(row) + ", " + std::to_string(column) + ") outside " +
                            std::to_string(rows_) + " x " + std::to_string(columns_));
  }
  const std::size_t i = row * columns_ + column;
  return {rms_of(sum_sq_m2_[i], samples_[i]), samples_[i]};
}

double ErrorMap::x_m(std::size_t column) const noexcept {
  return x_low_m_ + (static_cast<double>(column) + 0.5) * column_width_m_;
}

double ErrorMap::y_m(std::size_t row) const noexcept { return row < rows_ ? row_y_m_[row] : kNoError; }

ErrorMap build_error_map(const RasterSpec& spec, std::span<const double> t_s, std::span<const double> error_m,
                         const ErrorMapOptions& options) {
  spec.validate();
  options.validate();
  if (t_s.size() != error_m.size()) {
    throw ParameterError("error_m", std::to_string(error_m.size()) + " samples for " + std::to_string(t_s.size()) +
                                        " times (t_s): one error per time");
  }
  require_finite_samples("t_s", t_s);
  require_finite_samples("error_m", error_m);

  ErrorMap map(spec, options.columns);
  ErrorMapSummary& s = map.summary_;
  double sum_sq = 0.0, trace_sq = 0.0, retrace_sq = 0.0;
  const double columns = static_cast<double>(map.columns_);
  for (std::size_t i = 0; i < t_s.size(); ++i) {
    const RasterPoint p = raster_point(spec, t_s[i]);
    if (!p.on_straight) {
      ++s.skipped;
      continue;
    }
    // `along` runs with the line; the image's column runs from the fast axis's low end.
    const double from_low = p.direction > 0 ? p.along : 1.0 - p.along;
    const auto column = std::min(map.columns_ - 1, static_cast<std::size_t>(std::floor(from_low * columns)));
    const std::size_t cell = static_cast<std::size_t>(p.line) * map.columns_ + column;
    const double e2 = error_m[i] * error_m[i];
    map.sum_sq_m2_[cell] += e2;
    ++map.samples_[cell];
    sum_sq += e2;
    ++s.samples;
    if (p.direction > 0) {
      trace_sq += e2;
      ++s.trace_samples;
    } else {
      retrace_sq += e2;
      ++s.retrace_samples;
    }
  }
  s.rms_m = rms_of(sum_sq, s.samples);
  s.trace_rms_m = rms_of(trace_sq, s.trace_samples);
  s.retrace_rms_m = rms_of(retrace_sq, s.retrace_samples);

  std::size_t empty = 0;
  for (std::size_t row = 0; row < map.rows_; ++row) {
    for (std::size_t column = 0; column < map.columns_; ++column) {
      const ErrorCell c = map.cell(row, column);
      if (c.samples == 0) {
        ++empty;
      } else if (std::isnan(s.worst_rms_m) || c.rms_m > s.worst_rms_m) {
        s.worst_rms_m = c.rms_m;
        s.worst_row = row;
        s.worst_column = column;
      }
    }
  }
  s.empty_fraction = static_cast<double>(empty) / static_cast<double>(map.rows_ * map.columns_);
  return map;
}

PlotResult write_error_map(const ErrorMap& map, const std::filesystem::path& dir, const std::string& stem,
                           const std::string& title, const PlotOptions& options) {
  PlotResult result;
  {
    DataFile out(dir / (stem + ".dat"));
    out.text(
        "# x_µm y_µm rms_nm samples   (one row per cell of the error map; a blank line after each line of the "
        "raster; NaN: no sample)\n");
    for (std::size_t row = 0; row < map.rows(); ++row) {
      for (std::size_t column = 0; column < map.columns(); ++column) {
        const ErrorCell c = map.cell(row, column);
        out.num(map.x_m(column) * 1e6).num(map.y_m(row) * 1e6).num(c.rms_m * 1e9);
        out.integer(static_cast<long long>(c.samples));
        out.end_row();
      }
      out.blank_line();
    }
    result.data_files.push_back(out.close());
  }

  const ErrorMapSummary& s = map.summary();
  const double half_column_um = 0.5 * (map.x_m(1) - map.x_m(0)) * 1e6;
  const double x_lo_um = map.x_m(0) * 1e6 - half_column_um;
  const double x_hi_um = map.x_m(map.columns() - 1) * 1e6 + half_column_um;
  // With every line at one place gnuplot cannot lay the rows out by y: they are drawn by number.
  const bool by_line = !(map.height_m() > 0.0);
  const std::size_t last_row = map.rows() - 1;
  const double half_row = by_line ? 0.5 : 0.5 * (map.y_m(last_row) - map.y_m(0)) * 1e6 / static_cast<double>(last_row);
  const double y_lo = by_line ? -0.5 : map.y_m(0) * 1e6 - half_row;
  const double y_hi = by_line ? static_cast<double>(last_row) + 0.5 : map.y_m(last_row) * 1e6 + half_row;

  const std::string png = stem + ".png";
  std::ostringstream gp;
  gp << "# Re-plot with: cd <this folder> && gnuplot " << stem << ".gp   (terminal: edit the first line)\n"
     << "set terminal @TERMINAL@ size 900,800 noenhanced\nset encoding utf8\n"
     << "set output '" << png << "'\n"
     << "set title "
     << quoted(title + ": RMS " + nm_text(s.rms_m) + " (trace " + nm_text(s.trace_rms_m) + ", retrace " +
               nm_text(s.retrace_rms_m) + ") over " + std::to_string(s.samples) + " samples")
     << "\nset xlabel 'fast axis " << axis_name(map.fast_axis()) << " [µm]'\n"
     << "set ylabel '"
     << (by_line ? std::string("line") : "slow axis " + std::string(axis_name(map.slow_axis())) + " [µm]") << "'\n"
     << "set cblabel 'tracking error RMS [nm]'\nset cbrange [0:*]\n"
     // A sequential palette from dark (no error) to bright; an empty cell (NaN) stays blank.
     << "set palette defined (0 '#000004', 1 '#3b0f70', 2 '#8c2981', 3 '#de4968', 4 '#fe9f6d', 5 '#fcfdbf')\n"
     << "set xrange [" << plot_number(x_lo_um) << ":" << plot_number(x_hi_um) << "]\n"
     << "set yrange [" << plot_number(y_lo) << ":" << plot_number(y_hi) << "]\n"
     << "plot '" << stem << ".dat' using 1:" << (by_line ? "(column(-1))" : "2") << ":3 with image notitle\n"
     << "unset output\n";

  std::vector<std::string> images;
  if (s.samples > 0) images.push_back(png);
  render_script({stem + ".gp", gp.str(), images, stem + "_gnuplot.log", "error map",
                 "no sample on a straight part of the raster: error map not drawn"},
                dir, options, result);
  return result;
}

}  // namespace hystloop::report
