#pragma once
// Where hystloop-identify's results go (--out): a file takes the YAML snippet (as always); a
// folder -- one that exists, or a name ending in '/', made if missing -- takes config.yaml and the
// plots of the fit (fit_plots.hpp). Nothing is written unless the fit succeeded.

#include <filesystem>
#include <optional>
#include <string>

#include "fit_plots.hpp"

namespace hystloop {

struct OutputTarget {
  std::string yaml;                                // empty: print only
  std::optional<std::filesystem::path> plots_dir;  // a folder was given
};

OutputTarget output_target(const std::string& out);

// Prints the snippet, writes it to target.yaml; 0, or 2 when it cannot be written (the reason printed).
int write_yaml(const OutputTarget& target, const std::string& yaml);

// Writes the plots into target.plots_dir and says what was written; 0, or 2 when a file cannot
// be written. Missing gnuplot is a warning, not a failure: the data and the script are there.
int write_plots(const OutputTarget& target, const SampleTable& record, const FitPlotInput& input,
                const std::string& gnuplot);

}  // namespace hystloop
