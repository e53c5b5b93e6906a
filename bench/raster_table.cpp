// raster_table: an XY raster on the simulated XY stage, in process and faster than real time
// (common/sim/raster_experiment.hpp), the figures of docs/TRACKING.md's "XY rasters" and their
// error maps.
//
// The stage: two axes, each Banning's stage (Tables 1-2) with 1 nm RMS sensor noise of its own,
// x moving y by --coupling (3 % by default, a flexure stage's order). Per axis the loop of the
// line-rate scans (the model identified from a 10 Hz sine of a 1 um line's loops, the stage's
// inverse, the servo); the raster 1 um x 1 um, 64 lines at 50 lines/s, its slow axis stepping in
// the corners. Each axis follows its share of C^-1 r (decoupled) or r alone (coupled), with and
// without the servo, with the coupling identified on the stage (sim/raster_experiment.hpp,
// identify_coupling) instead of the true one, and with learning on the fast axis. Then a
// Lissajous figure, decoupled and coupled. RMS and max of r - y (the true position,
// against the path's reference) over the lines, per axis; the bridge's clamped ticks.
//
//   raster_table [--out DIR] [--lines N] [--line-rate HZ] [--coupling F] [--columns N]
//
// writes DIR/error_map_{decoupled,coupled}_{x,y}.{dat,gp,png} (PNG when gnuplot is installed).

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "core/errors.hpp"
#include "error_map.hpp"
#include "sim/raster_experiment.hpp"

namespace {

using namespace hystloop;

struct Row {
  const char* name;
  PathRun run;
};

void print_row(const Row& r) {
  if (r.run.refused) {
    std::printf("| %s | refused: %s | | | | |\n", r.name, r.run.reason.c_str());
    return;
  }
  std::printf("| %s | %.2f nm | %.1f nm | %.2f nm | %.1f nm | %llu |\n", r.name, r.run.stats[0].rms_true_m * 1e9,
              r.run.stats[0].max_abs_true_m * 1e9, r.run.stats[1].rms_true_m * 1e9, r.run.stats[1].max_abs_true_m * 1e9,
              static_cast<unsigned long long>(r.run.clamped_ticks));
  std::fflush(stdout);
}

void write_maps(const RasterRun& run, const std::string& label, const std::filesystem::path& dir, std::size_t columns) {
  report::ErrorMapOptions options;
  options.columns = columns;
  for (int axis = 0; axis < 2; ++axis) {
    const report::ErrorMap map =
        report::build_error_map(run.raster, run.t_s, run.error_m[static_cast<std::size_t>(axis)], options);
    const std::string name(axis_name(axis));
    const std::string title = fmt::format("{} ({} axis), {}", name, axis == 0 ? "fast" : "slow", label);
    const report::PlotResult plot =
        report::write_error_map(map, dir, fmt::format("error_map_{}_{}", label, name), title);
    for (const auto& image : plot.images) std::printf("  %s\n", image.string().c_str());
    if (!plot.warning.empty()) std::printf("  (%s)\n", plot.warning.c_str());
  }
}

}  // namespace

int run(int argc, char** argv) {
  CLI::App app{
      "raster_table: an XY raster on the simulated XY stage, in process; prints the per-axis table and "
      "writes the error maps"};
  std::filesystem::path out = "out/raster-table";
  RasterOptions o;
  std::size_t columns = 64;
  app.add_option("--out", out, "folder of the error maps")->capture_default_str();
  app.add_option("--lines", o.lines, "lines of the raster")
      ->check(CLI::Range(2, RasterSpec::kMaxLines))
      ->capture_default_str();
  app.add_option("--line-rate", o.line_rate_hz, "lines per second [Hz]")
      ->check(CLI::Range(0.1, 1000.0))
      ->capture_default_str();
  app.add_option("--coupling", o.coupling, "x -> y coupling of the stage [m/m]")
      ->check(CLI::Range(-kMaxCoupling, kMaxCoupling))
      ->capture_default_str();
  app.add_option("--columns", columns, "bins of the error maps along the fast axis")
      ->check(CLI::Range(4, 4096))
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // --help: 0; a usage error: 2, as the other tools
  }
  try {
    const TrackingExperiment e;
    const IdentifiedModels models = identify_for_scan(e, 0.5 * o.width_m);
    std::printf("XY raster %.3g um x %.3g um, %d lines at %g lines/s, x -> y coupling %g %%, model %s\n\n",
                o.width_m * 1e6, o.height_m * 1e6, o.lines, o.line_rate_hz, 100.0 * o.coupling,
                models.ranking.empty() ? "none" : std::string(to_string(models.ranking.front())).c_str());
    std::printf("| run | x (fast) RMS | x max | y (slow) RMS | y max | clamped ticks |\n");
    std::printf("| --- | --- | --- | --- | --- | --- |\n");
    const RasterRun decoupled = run_raster(e, models, o);
    print_row({"decoupled, servo", decoupled});
    o.decouple = false;
    const RasterRun coupled = run_raster(e, models, o);
    print_row({"coupled (no decoupling), servo", coupled});
    o.decouple = true;
    o.identified_decoupling = true;
    const RasterRun identified = run_raster(e, models, o);
    print_row({"decoupled with the identified coupling, servo", identified});
    o.identified_decoupling = false;
    o.learning = true;
    print_row({"decoupled, servo, learning", run_raster(e, models, o)});
    o.learning = false;
    o.loop.servo = false;
    print_row({"decoupled, feedforward only", run_raster(e, models, o)});
    o.decouple = false;
    print_row({"coupled, feedforward only", run_raster(e, models, o)});
    if (identified.coupling_fit && identified.coupling_fit->ok()) {
      const CouplingFitResult& f = *identified.coupling_fit;
      std::printf(
          "\nidentified coupling (each axis driven by 100 V at 5 Hz, servos off): x -> y %.5f +- %.1e, "
          "y -> x %.5f +- %.1e (the stage's: %.5f, 0)\n",
          f.estimate(1, 0), f.standard_error(1, 0), f.estimate(0, 1), f.standard_error(0, 1), o.coupling);
    }
    std::printf(
        "\nLissajous figure, 0.5 um at 50 Hz on x and 48 Hz on y, one second (each axis entered at its "
        "trough):\n\n| run | x RMS | x max | y RMS | y max | clamped ticks |\n| --- | --- | --- | --- | --- | --- |\n");
    LissajousOptions l;
    l.coupling = o.coupling;
    print_row({"decoupled, servo", run_lissajous(e, models, l)});
    l.decouple = false;
    print_row({"coupled (no decoupling), servo", run_lissajous(e, models, l)});
    std::printf("\nerror maps in %s:\n", out.string().c_str());
    std::filesystem::create_directories(out);
    if (!decoupled.refused) write_maps(decoupled, "decoupled", out, columns);
    if (!coupled.refused) write_maps(coupled, "coupled", out, columns);
  } catch (const std::exception& err) {
    std::fprintf(stderr, "raster_table: %s\n", err.what());
    return 1;
  }
  return 0;
}

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& err) {  // CLI11 building its options, or printing
    std::fprintf(stderr, "raster_table: %s\n", err.what());
    return 1;
  }
}
