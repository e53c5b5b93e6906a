// The raster error map on synthetic scans: 8 lines of 1 µm x 1 µm at 50 lines/s with 1 ms corners,
// sampled at 10 kHz, each with an error field whose value per cell is known. Which samples lie on
// a straight part and which column they fall in is worked out here from the geometry (the line
// times and the evaluated fast-axis position), not from raster_point, so a mistake there or in
// the binning shows. The map's files are read back; the PNG only where gnuplot is installed.
#include "error_map.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/errors.hpp"
#include "log_test_support.hpp"

namespace fs = std::filesystem;
using namespace hystloop;
using namespace hystloop::report;
using hystloop::test::is_png;
using hystloop::test::slurp;

namespace {

constexpr double kDt = 1e-4;
constexpr double kNm = 1e-9;
constexpr std::size_t kColumns = 16;

RasterSpec test_raster() {
  return {.width_m = 1e-6,
          .height_m = 1e-6,
          .lines = 8,
          .line_rate_hz = 50.0,
          .corner_s = 1e-3,
          .centre_m = {2e-6, -3e-6, 0.0},
          .settle_s = 0.01,
          .start_s = 0.005};
}

// A sample as the test sees it, from the geometry alone.
struct Sample {
  double t_s = 0.0;
  double x_m = 0.0;  // the fast axis's reference
  int line = -1;     // -1 before the start, lines after the last line
  bool straight = false;
  std::size_t column = 0;  // from x (meaningful when straight)
};

// Times half a tick off the grid, so that no sample sits on a corner's edge (those are on it).
std::vector<Sample> samples(const RasterSpec& spec, std::size_t columns, double until_s) {
  std::vector<Sample> out;
  const double x_low_m = spec.centre_m[0] - 0.5 * spec.width_m;
  for (std::size_t k = 0;; ++k) {
    Sample s;
    s.t_s = (static_cast<double>(k) + 0.5) * kDt;
    if (s.t_s > until_s) break;
    s.x_m = evaluate(spec, s.t_s)[0];
    const double tau_s = s.t_s - spec.start_s;
    s.line = tau_s < 0.0 ? -1 : static_cast<int>(std::floor(tau_s * spec.line_rate_hz));
    const double within_s = tau_s - s.line / spec.line_rate_hz;
    s.straight = s.line >= 0 && s.line < spec.lines && within_s >= 0.5 * spec.corner_s &&
                 within_s <= 1.0 / spec.line_rate_hz - 0.5 * spec.corner_s;
    const double bin = std::floor((s.x_m - x_low_m) / spec.width_m * static_cast<double>(columns));
    s.column = static_cast<std::size_t>(std::clamp(bin, 0.0, static_cast<double>(columns - 1)));
    out.push_back(s);
  }
  return out;
}

double whole_scan_s(const RasterSpec& spec) { return spec.start_s + raster_duration_s(spec) + 0.005; }

struct Field {
  std::vector<double> t_s, error_m;
};

Field field(const std::vector<Sample>& ss, const std::function<double(const Sample&)>& error_of) {
  Field f;
  for (const Sample& s : ss) {
    f.t_s.push_back(s.t_s);
    f.error_m.push_back(error_of(s));
  }
  return f;
}

ErrorMap build(const RasterSpec& spec, const Field& f, std::size_t columns = kColumns) {
  return build_error_map(spec, f.t_s, f.error_m, ErrorMapOptions{columns});
}

template <class F>
std::string refused_field(F&& f) {
  try {
    f();
  } catch (const ParameterError& e) {
    return e.field();
  }
  return "(accepted)";
}

fs::path scratch_dir(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("hystloop_error_map_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

bool have_gnuplot() { return std::system("command -v gnuplot >/dev/null 2>&1") == 0; }

}  // namespace

// Trace 1 nm, retrace 3 nm on the straight parts; 1 m everywhere else, so a single corner,
// approach or settle sample that got in would dwarf every figure.
TEST(ErrorMap, TraceAndRetraceAreSummedApartAndCornersAndSettleAreLeftOut) {
  const RasterSpec spec = test_raster();
  const auto ss = samples(spec, kColumns, whole_scan_s(spec));
  const ErrorMap map = build(spec, field(ss, [](const Sample& s) {
                               if (!s.straight) return 1.0;
                               return s.line % 2 == 0 ? 1 * kNm : 3 * kNm;
                             }));
  std::size_t straight = 0, trace = 0;
  for (const Sample& s : ss) {
    straight += s.straight ? 1 : 0;
    trace += s.straight && s.line % 2 == 0 ? 1 : 0;
  }
  const ErrorMapSummary& sum = map.summary();
  ASSERT_GT(straight, 8u * 150u);  // nearly 190 a line
  EXPECT_EQ(sum.samples, straight);
  EXPECT_EQ(sum.skipped, ss.size() - straight);
  EXPECT_EQ(sum.trace_samples, trace);
  EXPECT_EQ(sum.retrace_samples, straight - trace);
  EXPECT_NEAR(sum.trace_rms_m, 1 * kNm, 1e-21);
  EXPECT_NEAR(sum.retrace_rms_m, 3 * kNm, 1e-21);
  const double n_trace = static_cast<double>(trace), n_retrace = static_cast<double>(straight - trace);
  EXPECT_NEAR(sum.rms_m, kNm * std::sqrt((n_trace * 1 + n_retrace * 9) / (n_trace + n_retrace)), 1e-21);
  ASSERT_EQ(map.rows(), 8u);
  ASSERT_EQ(map.columns(), kColumns);
  EXPECT_EQ(sum.empty_fraction, 0.0);
  for (std::size_t row = 0; row < map.rows(); ++row) {
    for (std::size_t column = 0; column < map.columns(); ++column) {
      EXPECT_NEAR(map.cell(row, column).rms_m, (row % 2 == 0 ? 1 : 3) * kNm, 1e-21) << row << ", " << column;
    }
  }
}

// e = a (x - centre) + b on trace and its negative on retrace: the same |e| at the same place,
// so every cell of every line holds the RMS of the field over where its samples were, and
// column 0 is the low end on retrace too (reversed, it would hold the high end's 25 nm).
TEST(ErrorMap, LinearFieldGivesEachCellTheExactRmsOfItsSamples) {
  const RasterSpec spec = test_raster();
  constexpr double kSlope = 0.02;  // 20 nm over the 1 µm line: 5 nm at the low end, 25 nm at the high
  constexpr double kOffset = 15 * kNm;
  const auto ss = samples(spec, kColumns, whole_scan_s(spec));
  const auto value = [&](double x_m) { return kSlope * (x_m - spec.centre_m[0]) + kOffset; };
  const ErrorMap map =
      build(spec, field(ss, [&](const Sample& s) { return (s.line % 2 == 0 ? 1 : -1) * value(s.x_m); }));

  std::vector<double> sum_sq(8 * kColumns, 0.0);
  std::vector<std::size_t> n(8 * kColumns, 0);
  for (const Sample& s : ss) {
    if (!s.straight) continue;
    const std::size_t i = static_cast<std::size_t>(s.line) * kColumns + s.column;
    sum_sq[i] += value(s.x_m) * value(s.x_m);
    ++n[i];
  }
  const double x_low_m = spec.centre_m[0] - 0.5 * spec.width_m, column_m = spec.width_m / kColumns;
  for (std::size_t row = 0; row < 8; ++row) {
    for (std::size_t column = 0; column < kColumns; ++column) {
      const ErrorCell c = map.cell(row, column);
      const std::size_t i = row * kColumns + column;
      ASSERT_GT(n[i], 0u);
      EXPECT_EQ(c.samples, n[i]) << row << ", " << column;
      EXPECT_NEAR(c.rms_m, std::sqrt(sum_sq[i] / static_cast<double>(n[i])), 1e-12 * kOffset) << row << ", " << column;
      // The field is increasing and positive: its RMS over a column lies between its ends there.
      const double lo = value(x_low_m + static_cast<double>(column) * column_m);
      EXPECT_GE(c.rms_m, lo - 1e-21) << row << ", " << column;
      EXPECT_LE(c.rms_m, lo + kSlope * column_m + 1e-21) << row << ", " << column;
    }
  }
  EXPECT_NEAR(map.summary().trace_rms_m, map.summary().retrace_rms_m, 0.02 * kOffset);
  EXPECT_EQ(map.summary().worst_column, kColumns - 1);

  EXPECT_NEAR(map.x_m(0), x_low_m + 0.5 * column_m, 1e-18);
  EXPECT_NEAR(map.x_m(kColumns - 1), spec.centre_m[0] + 0.5 * spec.width_m - 0.5 * column_m, 1e-18);
  for (std::size_t row = 0; row < 8; ++row) {  // the steps: one line spacing apart from the bottom
    EXPECT_NEAR(map.y_m(row), spec.centre_m[1] - 0.5 * spec.height_m + static_cast<double>(row) * spec.height_m / 7,
                1e-15)
        << row;
  }
}

TEST(ErrorMap, HotSpotLandsInItsCell) {
  const RasterSpec spec = test_raster();
  constexpr int kLine = 5;
  constexpr std::size_t kColumn = 11;
  const double column_m = spec.width_m / kColumns;
  const double spot_from_m = spec.centre_m[0] - 0.5 * spec.width_m + (kColumn + 0.25) * column_m;
  const auto ss = samples(spec, kColumns, whole_scan_s(spec));
  const ErrorMap map = build(spec, field(ss, [&](const Sample& s) {
                               const bool in_spot =
                                   s.line == kLine && s.x_m >= spot_from_m && s.x_m <= spot_from_m + 0.5 * column_m;
                               return in_spot ? 40 * kNm : 1 * kNm;
                             }));
  const ErrorMapSummary& sum = map.summary();
  EXPECT_EQ(sum.worst_row, static_cast<std::size_t>(kLine));
  EXPECT_EQ(sum.worst_column, kColumn);
  EXPECT_GT(sum.worst_rms_m, 20 * kNm);
  EXPECT_EQ(sum.worst_rms_m, map.cell(kLine, kColumn).rms_m);
  for (const auto& [row, column] : {std::pair<std::size_t, std::size_t>{kLine, kColumn - 1},
                                    {kLine, kColumn + 1},
                                    {kLine - 1, kColumn},
                                    {kLine + 1, kColumn}}) {
    EXPECT_NEAR(map.cell(row, column).rms_m, 1 * kNm, 1e-21) << row << ", " << column;
  }
}

TEST(ErrorMap, CellsWithoutSamplesAreNaN) {
  const RasterSpec spec = test_raster();
  // Samples up to the middle of line 4's corner: lines 0..3 are complete, 4..7 have none.
  const auto ss = samples(spec, kColumns, spec.start_s + 4.0 / spec.line_rate_hz);
  const ErrorMap map = build(spec, field(ss, [](const Sample&) { return 2 * kNm; }));
  EXPECT_EQ(map.summary().empty_fraction, 0.5);
  for (std::size_t row = 0; row < 8; ++row) {
    for (std::size_t column = 0; column < kColumns; ++column) {
      const ErrorCell c = map.cell(row, column);
      if (row < 4) {
        EXPECT_NEAR(c.rms_m, 2 * kNm, 1e-21);
      } else {
        EXPECT_TRUE(std::isnan(c.rms_m)) << row << ", " << column << ": " << c.rms_m;
        EXPECT_EQ(c.samples, 0u);
      }
    }
  }
  // At the finest binning a line's 190 samples leave most of its 4096 cells empty.
  const ErrorMap fine = build(spec, field(ss, [](const Sample&) { return 2 * kNm; }), 4096);
  EXPECT_GT(fine.summary().empty_fraction, 0.95);

  const ErrorMap none = build(spec, Field{});
  EXPECT_EQ(none.summary().samples, 0u);
  EXPECT_EQ(none.summary().empty_fraction, 1.0);
  EXPECT_TRUE(std::isnan(none.summary().rms_m));
  EXPECT_TRUE(std::isnan(none.summary().trace_rms_m));
  EXPECT_TRUE(std::isnan(none.summary().worst_rms_m));
  EXPECT_THROW((void)none.cell(8, 0), std::out_of_range);
  EXPECT_THROW((void)none.cell(0, kColumns), std::out_of_range);
}

TEST(ErrorMap, RefusesBadColumnsLengthsValuesAndSpecs) {
  const RasterSpec spec = test_raster();
  const std::vector<double> t{0.01, 0.02, 0.03}, e{1e-9, 2e-9, 3e-9};
  for (const std::size_t columns : {0u, 3u, 4097u}) {
    EXPECT_EQ(refused_field([&] { (void)build_error_map(spec, t, e, ErrorMapOptions{columns}); }), "error_map.columns")
        << columns;
  }
  for (const std::size_t columns : {4u, 4096u}) {
    EXPECT_NO_THROW((void)build_error_map(spec, t, e, ErrorMapOptions{columns})) << columns;
  }
  try {
    (void)build_error_map(spec, t, std::span<const double>(e).first(2), ErrorMapOptions{});
    ADD_FAILURE() << "accepted 2 errors for 3 times";
  } catch (const ParameterError& err) {
    EXPECT_EQ(err.field(), "error_m");
    EXPECT_NE(std::string(err.what()).find("2 samples for 3 times"), std::string::npos) << err.what();
  }
  std::vector<double> bad_t = t, bad_e = e;
  bad_t[1] = std::nan("");
  bad_e[2] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(refused_field([&] { (void)build_error_map(spec, bad_t, e, ErrorMapOptions{}); }), "t_s[1]");
  EXPECT_EQ(refused_field([&] { (void)build_error_map(spec, t, bad_e, ErrorMapOptions{}); }), "error_m[2]");
  RasterSpec one_line = spec;
  one_line.lines = 1;
  EXPECT_EQ(refused_field([&] { (void)build_error_map(one_line, t, e, ErrorMapOptions{}); }), "raster.lines");
}

// The data file holds one row per cell, a block per line; the script draws it with the colour
// bar named; gnuplot renders it.
TEST(ErrorMap, WritesDataScriptAndImage) {
  const RasterSpec spec = test_raster();
  // Six lines sampled: the last two rows stay empty (NaN in the data).
  const auto ss = samples(spec, kColumns, spec.start_s + 6.0 / spec.line_rate_hz);
  const ErrorMap map = build(spec, field(ss, [](const Sample& s) { return (1.0 + s.line) * kNm; }));
  const fs::path dir = scratch_dir("write");
  const PlotResult result = write_error_map(map, dir, "error_map_x", "Raster 1 µm, it's MEM");

  std::istringstream dat(slurp(dir / "error_map_x.dat"));
  std::size_t rows = 0, blocks = 0, nan = 0;
  bool in_block = false;
  for (std::string line; std::getline(dat, line);) {
    if (line.starts_with("#")) continue;
    if (line.empty()) {
      blocks += in_block ? 1 : 0;
      in_block = false;
      continue;
    }
    in_block = true;
    std::istringstream fields(line);
    std::string x, y, rms, n, extra;
    ASSERT_TRUE(fields >> x >> y >> rms >> n) << line;
    EXPECT_FALSE(fields >> extra) << line;
    EXPECT_TRUE(std::isfinite(std::stod(x)) && std::isfinite(std::stod(y))) << line;
    if (rms == "NaN") {
      ++nan;
      EXPECT_EQ(n, "0") << line;
    } else {
      const std::size_t row = rows / kColumns;
      EXPECT_NEAR(std::stod(rms), 1.0 + static_cast<double>(row), 1e-6) << line;  // nm
      EXPECT_NEAR(std::stod(y), map.y_m(row) * 1e6, 1e-6) << line;                // µm
    }
    ++rows;
  }
  EXPECT_EQ(rows, map.rows() * map.columns());
  EXPECT_EQ(blocks, map.rows());
  EXPECT_EQ(nan, 2 * kColumns);

  const std::string gp = slurp(dir / "error_map_x.gp");
  EXPECT_NE(gp.find("set cblabel 'tracking error RMS [nm]'"), std::string::npos) << gp;
  EXPECT_NE(gp.find("'error_map_x.dat' using 1:2:3 with image"), std::string::npos) << gp;
  EXPECT_NE(gp.find("set title 'Raster 1 µm, it''s MEM: RMS " + number_text(map.summary().rms_m * 1e9, 3) + " nm"),
            std::string::npos)
      << gp;
  EXPECT_NE(gp.find("set output 'error_map_x.png'"), std::string::npos) << gp;
  ASSERT_EQ(result.data_files.size(), 1u);
  EXPECT_EQ(result.script, dir / "error_map_x.gp");

  if (!have_gnuplot()) GTEST_SKIP() << "no gnuplot";
  EXPECT_EQ(result.warning, "");
  ASSERT_EQ(result.images.size(), 1u) << slurp(dir / "error_map_x_gnuplot.log");
  EXPECT_TRUE(is_png(dir / "error_map_x.png"));
  EXPECT_EQ(slurp(dir / "error_map_x_gnuplot.log"), "");  // not even a warning
  if (std::getenv("HYSTLOOP_KEEP_TEST_OUTPUT") == nullptr) fs::remove_all(dir);
}

TEST(ErrorMap, WithoutGnuplotTheDataAndScriptAreStillWritten) {
  const RasterSpec spec = test_raster();
  const auto ss = samples(spec, kColumns, whole_scan_s(spec));
  const ErrorMap map = build(spec, field(ss, [](const Sample&) { return kNm; }));
  const fs::path dir = scratch_dir("nognuplot");
  PlotOptions options;
  options.gnuplot = "/nonexistent/gp";
  const PlotResult result = write_error_map(map, dir, "map", "no gnuplot", options);
  EXPECT_NE(result.warning.find("gnuplot not found"), std::string::npos) << result.warning;
  EXPECT_TRUE(result.images.empty());
  EXPECT_TRUE(fs::exists(dir / "map.dat"));
  EXPECT_TRUE(fs::exists(dir / "map.gp"));
  EXPECT_FALSE(fs::exists(dir / "map.png"));
  fs::remove_all(dir);
}

// Every line at one height: the rows are drawn by line number, which gnuplot can lay out.
TEST(ErrorMap, FlatRasterIsDrawnByLine) {
  RasterSpec spec = test_raster();
  spec.height_m = 0.0;
  const auto ss = samples(spec, kColumns, whole_scan_s(spec));
  const ErrorMap map = build(spec, field(ss, [](const Sample& s) { return (1.0 + s.line) * kNm; }));
  for (std::size_t row = 0; row < map.rows(); ++row) EXPECT_EQ(map.y_m(row), spec.centre_m[1]);
  const fs::path dir = scratch_dir("flat");
  const PlotResult result = write_error_map(map, dir, "flat", "flat");
  const std::string gp = slurp(dir / "flat.gp");
  EXPECT_NE(gp.find("using 1:(column(-1)):3 with image"), std::string::npos) << gp;
  EXPECT_NE(gp.find("set ylabel 'line'"), std::string::npos) << gp;
  if (!have_gnuplot()) GTEST_SKIP() << "no gnuplot";
  EXPECT_EQ(result.warning, "");
  EXPECT_TRUE(is_png(dir / "flat.png")) << slurp(dir / "flat_gnuplot.log");
  fs::remove_all(dir);
}
