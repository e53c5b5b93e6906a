#pragma once
// The MEM model's position for the logged voltages, for the u -> y plot: the measured loop with
// the loop the model in use predicts for the same u on top of it.
//
// The set of a tick: for a tick of an identification experiment (MODE_EXPERIMENT) the first
// valid MEM set published after it with a fit residual (the one fitted from it; a set sent by
// hand carries none);
// else its command's params_version
// when that is a valid MEM set of the report, else the latest valid MEM set published at or
// before the tick, else the first valid MEM set of the report. The model starts on its skeleton
// at the first tick's u, offset to pass through the first measured y; a change of set keeps the
// current point (MemModel::set_params), as the compensator's swap does; at each reversal of u
// the model's branch is moved to start at the measured y, so that the plot compares branch
// shapes and does not accumulate the offset of a long open-loop run.

#include <vector>

#include "report_metrics.hpp"

namespace hystloop::report {

// One y [m] per tick, NaN where no set applies; empty when the report has no valid MEM set.
std::vector<double> mem_model_y(const std::vector<TrackPoint>& ticks, const ReportMetrics& metrics);

}  // namespace hystloop::report
