#pragma once
// hystloop-identify's plots (--out DIR): data files and a gnuplot script written into DIR (so a
// user can edit and re-run `gnuplot plots.gp` there), rendered with gnuplot's pngcairo terminal,
// or its libgd png terminal where cairo is missing.
//   loop_u_y.png     measured and model loops, u -> y, over the record
//   residual.png     measured - model against time; the held-out branch in its own colour
//   heldout_u_y.png  the held-out branch alone: measured and predicted (a model fitted without it)
//   candidates.png   --model auto: every model fitted, side by side, with its held-out RMS
// Data files, one per curve (fit_<model>.dat; heldout_<model>.dat for a single model's fit on the
// record's first part), in SI units, columns:
//   t_s u_V y_measured_m y_model_m residual_m heldout
// residual = measured - model (NaN where the model has no state yet), heldout 1 for samples the
// model was not fitted to. The plots convert to µm and nm.

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "fit_curves.hpp"
#include "ident/sample_csv.hpp"
#include "plots.hpp"  // tools/report: PlotResult

namespace hystloop {

struct FitPlotInput {
  std::string heading;               // the first line of every plot's title, e.g. the input file
  FitCurve chosen;                   // the set written to the config, over the record
  std::optional<FitCurve> heldout;   // a single model fitted on the first part, predicting the rest
  std::vector<FitCurve> candidates;  // --model auto: every model fitted and scored, best first
};

struct FitPlotOptions {
  std::string gnuplot = "gnuplot";   // executable, searched in PATH unless it contains '/'
  std::size_t max_points = 200'000;  // rows per data file at most (every K-th sample beyond)
};

// The data files and the script, always written; the PNGs gnuplot rendered, its terminal, and why
// images are missing (empty when all went well).
using FitPlotFiles = report::PlotResult;

// Writes the data and the script into `dir` (which must exist) and runs gnuplot there.
// Throws std::runtime_error naming the file that cannot be written.
FitPlotFiles write_fit_plots(const SampleTable& record, const FitPlotInput& input, const std::filesystem::path& dir,
                             const FitPlotOptions& options = {});

}  // namespace hystloop
