#pragma once
// hystloop-ctl experiment coupling: the cross-coupling of an XY(Z) stage, identified on the rig the
// way ident/coupling_fit.hpp asks. Each axis in turn is driven by a sine (a compensator
// experiment on that axis) while the others hold their references, with the bridge's servo off
// (a servo would hold the other axes against the very coupling to be measured), and every axis's
// sensor is recorded; the servo's gains are put back afterwards, whatever happened. The fit gives
// C with standard errors, printed, and written as the compensator's decoupling.* keys.

#include <array>
#include <string>
#include <vector>

#include "ctl_link.hpp"
#include "ident/coupling_fit.hpp"

namespace hystloop::ctl {

struct CouplingRunOptions {
  double amplitude_V = 100.0;  // each axis's sine [V]
  // ... about this voltage [V]: a unipolar stage (e.g. -20 .. +150 V) runs it inside its range.
  // The fit takes the slopes between the sensors, so the offset changes nothing but where.
  double offset_V = 0.0;
  double frequency_Hz = 5.0;
  double duration_s = 0.8;  // four periods at 5 Hz
  double rest_s = 1.0;      // after an axis's experiment, before the next: the axis comes back to rest
  std::string bridge_process = "bridge";
  std::string compensator_process = "compensator";
  std::string out;         // YAML file for the compensator (--params), empty: none
  double timeout_s = 5.0;  // for each answer and beyond each experiment's duration
  void validate() const;   // throws ParameterError naming the option
};

// One axis's experiment of the run: the sine the options give (its axis set by the caller).
ExperimentRequest coupling_experiment(const CouplingRunOptions& o);

// The samples of one axis's experiment: every axis's sensor at the ticks the moved axis ran it
// (no reference: y_ref NaN, and a voltage applied).
struct CouplingRecord {
  int axis = 0;
  std::array<std::vector<double>, kMaxAxes> y_m;
};

// Fits the records of a stage of `axes` axes (fit_coupling) and formats the result: the matrix
// with standard errors, one line per entry, for the terminal.
CouplingFitResult fit_records(const std::vector<CouplingRecord>& records, int axes);
std::string describe_fit(const CouplingFitResult& fit, int axes);
// The compensator's keys for a fit: "decoupling:\n  x_to_y: ...\n" (every off-diagonal entry of the
// stage's axes), with a comment saying where it came from.
std::string decoupling_yaml(const CouplingFitResult& fit, int axes, const std::string& origin);

// Runs it on the rig: returns 0 when every axis was excited and the fit holds, 1 otherwise (the
// reason printed). The servo's gains in force are put back in every case once they were changed.
int run_coupling_experiment(CtlLink& link, const CouplingRunOptions& options);

}  // namespace hystloop::ctl
