// hystloop-identify data.csv|run.NNN.lcmlog... --model mem|banning|katalenic|pi|linear|auto
//                   [--form integrated|derivative] [--out params.yaml | --out DIR/ [--gnuplot EXE]]
//                   [--log] [--rig HX_] [--dt 1e-4 | --time-from utime] [--from S] [--to S]
//                   [--experiment N] [--compensator NAME --max-late F --max-missing F]   (experiments on logs)
//                   [--publish [--publish-on params|model] [--version N] [--listen-s 0.5] [--lcm-url URL]
//                              [--allow-network] [--key-file F] [--timeout 5 | --no-wait]]
//                   [--max-samples 2000000] [--decimate K] [--progress]
// hystloop-identify data.csv|run.lcmlog --model stage [--period-samples N --periods P --realisations R
//                   --skip S --sample-rate HZ] [--band F1:F2] [--order NUM/DEN | auto] [--out DIR/]
//                   the stage's linear dynamics from a multisine record (identify_stage.hpp)
// Input: CSV t,u,y (sample_csv.hpp), or LCM event logs (files ending in .lcmlog, or --log): the
// rig's HX_SENSOR samples, several rotated files concatenated in the order given (log_samples.hpp);
// for --model banning, the experiments the loop ran, found by their requests (log_experiments.hpp).
// A log with several experiments and none chosen (--experiment N, or --from/--to) is not fitted:
// they are listed (index, kind, amplitude, frequency, duration, time range), exit 2.
// --out DIR (a folder) writes config.yaml and the plots of the fit there (fit_plots.hpp).
// --publish sends the fitted set on HX_MODEL (any model) or, for --model mem, on HX_PARAMS, then
// waits until the compensator reports it in use (params_publish.hpp, adoption_watch.hpp).
// Memory bound (sample_budget.hpp): more than --max-samples samples (after --decimate) are refused
// with the reason and the ways out, before any fit (a CSV before it is even read). Progress
// (fit_progress.hpp): every 2 s on stderr while a stage runs, with --progress or when stderr is a
// terminal. A fit that is not a fit (non-finite residual, parameters outside the model's domain)
// is refused by the fitter (ident/fit_checks.hpp); samples beyond +-10 kV / +-1 m by the reader.
// Options: identify_args.hpp; the work: identify_run.hpp.
// Exit status (core/cli.hpp): 0 fitted (and published and adopted, or published with --no-wait);
// 1 no fit (the data cannot support one; the reason is printed, nothing published), or fitted
// but not published, or published but not adopted within --timeout; 2 usage (a log with several
// experiments and none chosen among them), or a file that cannot be used (not found, a folder,
// malformed, beyond the sanity bounds, too many samples), or an LCM setup error.
#include <CLI/CLI.hpp>

#include <iostream>

#include "core/cli.hpp"
#include "identify_args.hpp"
#include "identify_run.hpp"

namespace {

int run(int argc, char** argv) {
  using namespace hystloop;
  CLI::App app{
      "Fit a hysteresis model to recorded samples: a CSV with a header row t,u,y (s, V, m), or LCM event logs "
      "(*.lcmlog or --log: the rig's HX_SENSOR samples; rotated files in recording order).\n"
      "Exit status: 0 fitted (published and adopted, or published with --no-wait); 1 no fit, not published, or "
      "not adopted within --timeout; 2 usage (also: a log with several experiments and none chosen), a file "
      "that cannot be used, or an LCM setup error."};
  IdentifyArgs args;
  add_identify_options(app, args);
  if (const auto exit_code = parse_cli(app, argc, argv)) return *exit_code;
  if (const auto problem = check_identify_args(args)) {
    std::cerr << "hystloop-identify: " << *problem << "\n";
    return kExitUsage;
  }
  return run_identify(args);
}

}  // namespace

int main(int argc, char** argv) {
  return hystloop::run_tool("hystloop-identify", [&] { return run(argc, argv); });
}
