#pragma once
// The MEM model's position for the logged voltages, for the u -> y plot: the measured loop with
// the loop the model in use predicts for the same u on top of it.
//
// The set of a tick: its command's params_version when that is a valid MEM set of the report,
// else the latest valid MEM set published at or before the tick, else the first valid MEM set
// of the report (the identification experiment comes before the set fitted to it, so its ticks
// get the loop identified from them). The model starts on its skeleton at the first tick's u,
// offset to pass through the first measured y; a change of set keeps the current point
// (MemModel::set_params), as the compensator's swap does.

#include <vector>

#include "report_metrics.hpp"

namespace hystloop::report {

// One y [m] per tick, NaN where no set applies; empty when the report has no valid MEM set.
std::vector<double> mem_model_y(const std::vector<TrackPoint>& ticks, const ReportMetrics& metrics);

}  // namespace hystloop::report
