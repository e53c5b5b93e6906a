#pragma once
// What a user judges a fit by: the fitted model's forward simulation over the record, as
// model_selection.cpp scores it (MEM from its first reversal with the measured output there, PI
// with every play centred on u[0], Katalenic from its reset at u[0]), next to the measured y.
// A curve on a held-out part carries the offset the ranking removes (the mean of y - model over
// the training part after its second reversal), so the plot shows what the score measured.
// No files and no gnuplot here (fit_plots.hpp writes them).

#include <cstddef>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "ident/model_selection.hpp"
#include "models/model_set.hpp"

namespace hystloop {

struct FitCurve {
  ModelKind kind = ModelKind::mem;
  std::vector<double>
      y_model_m;  // one per sample; NaN where the model has no state yet (MEM before its first reversal)
  std::size_t heldout_begin = 0;  // samples from here on were not fitted (== size: every sample was)
  double offset_m = 0.0;          // added to the simulation (the ranking's offset; 0 for a fit on the whole record)
  double heldout_rms_m = std::numeric_limits<double>::quiet_NaN();  // NaN: nothing held out
};

// The model `fit` holds for `kind` (fit_candidate on the whole record): heldout_begin = size, no offset.
FitCurve whole_record_curve(const ModelSelection& fit, ModelKind kind, std::span<const double> u_V,
                            std::span<const double> y_m);

// One curve per candidate select_model fitted and scored (refused ones left out), in its
// ranking's order: each fitted on [0, split_index], the rest held out.
std::vector<FitCurve> ranked_curves(const ModelSelection& selection, std::span<const double> u_V,
                                    std::span<const double> y_m);

}  // namespace hystloop
