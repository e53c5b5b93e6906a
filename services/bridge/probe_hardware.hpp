#pragma once
// hystloop-bridge --probe-hardware: what a lab runs before the loop. Lists the comedi card
// (driver, board, every subdevice with its channels, ranges and flags, the calibration file
// and whether the configured channels are soft-calibrated); with --yes it also drives the
// configured output with a slow triangle of ±amplitude at the card around the safe voltage
// (clamped to the actuator's range and the DAC's), reads the sensor at every step and reports
// the sensor's gain and sign against the command, so wiring mistakes show before the loop runs.
// The output starts and ends at the safe voltage. On a stage of several axes it drives one axis
// (`axis`, x by default) while every other output holds its safe voltage.

#include <cstdio>
#include <string>

#include "bridge/bridge_settings.hpp"

namespace hystloop {

struct ProbeOptions {
  bool drive = false;        // --yes
  double amplitude_V = 1.0;  // at the card's output [V]
  double duration_s = 1.0;   // one triangle: safe -> +A -> -A -> safe
  double rate_hz = 1000.0;   // steps of the triangle
  int axis = 0;              // the axis driven (0 x, 1 y, 2 z; below bridge.axes)
};

// Writes the report to `out`. Returns 0, 1 (the card could not be opened / a read failed) or 2
// (the configuration is refused: a field the card does not have).
int probe_hardware(const BridgeSettings& settings, const ProbeOptions& options, std::FILE* out);

// The fit of the triangle check: sensor volts against card volts.
struct ProbeFit {
  double gain_V_per_V = 0.0;  // slope (sign: + when the sensor rises with the command)
  double offset_V = 0.0;
  double r = 0.0;  // correlation coefficient
  int samples = 0;
  int faults = 0;
};

}  // namespace hystloop
