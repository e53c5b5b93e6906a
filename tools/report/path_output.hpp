#pragma once
// What hystloop-report writes for the paths of HX_SCAN (path_figures.hpp), into the output folder:
//   raster.csv             one row per measured path and axis of the stage: RMS and max of
//                          r_a - position [m], the position used, the ticks, the loop time, the
//                          corner and its source, max |y_ref - r_a|; one row for a path not measured,
//                          with why
//   error_map_<axis>.png   per axis of a measured raster, the error map (error_map.hpp) with its
//                          .dat and .gp; error_map_v<version>_<axis> for a log of several rasters
//   summary.json           "scan_paths": the same figures (paths_json)
// and the table printed after the report's others.

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "error_map.hpp"
#include "path_figures.hpp"
#include "plots.hpp"

namespace hystloop::report {

// The printed table: one row per path and axis, a path not measured with why, then a line per
// path of where it ran and what it was measured against.
std::string path_table(const std::vector<PathFigures>& paths);

// raster.csv's text.
std::string path_csv(const std::vector<PathFigures>& paths);

// summary.json's "scan_paths".
nlohmann::ordered_json paths_json(const std::vector<PathFigures>& paths);

// The warnings a path's measurement calls for: ticks missing, an interruption, a logged y_ref that
// is not the path found (reference_mismatch_m above a picometre).
std::vector<std::string> path_warnings(const std::vector<PathFigures>& paths);

// The error map of every axis of every measured raster, as described above. Throws
// std::runtime_error if a file cannot be written; a missing gnuplot is PlotResult::warning.
PlotResult write_path_maps(const std::vector<PathFigures>& paths, const std::filesystem::path& dir,
                           const ErrorMapOptions& map, const PlotOptions& plots);

}  // namespace hystloop::report
