#pragma once
// hystloop-identify --model stage: a stage's linear dynamics from a periodic multisine record.
//
// Input: the compensator's multisine experiment in an LCM log (hystloop-ctl experiment multisine;
// its layout, lines and fade-in come from the logged request, as the compensator designed it), or
// a CSV recorded elsewhere (t,u,y, or u,y with --sample-rate) whose layout the command line gives
// (--period-samples, --periods, --realisations, --skip for samples before the record; --band for
// the lines, else the lines u excites).
// Work: the robust method's FRF with its uncertainty (ident/frequency_response.hpp), then the
// rational model with delay (ident/stage_fit.hpp) weighted by sigma_total (sigma_noise with one
// realisation), of the order given (--order NUM/DEN) or chosen, with the exact zero-order hold of a
// bridge unless --continuous. By default through the hysteresis (ident/stage_hysteresis_fit.hpp):
// a Prandtl-Ishlinskii model of --hysteresis-plays plays fitted together with the stage, and the
// FRF and fit from its output to y (--hysteresis-plays 0: from u -> y alone).
// Output: a YAML stage section in LinearStageSpec's zero/pole form (models/linear_stage.hpp):
//   stage:
//     zeros_hz: [[re, im], ...]   # s = 2 pi (re + i im); im != 0 stands for its conjugate pair
//     poles_hz: [[re, im], ...]
//     delay_s: ...
// with the fit's figures as comments (and on stdout): the measured DC gain u -> y (the hysteresis
// model carries it; the stage model has unit DC gain), chi-square per line against its
// expectation, and every order tried. With --out DIR: config.yaml there, the FRF's data
// (stage_frf.dat) and Bode plots: stage_bode.png (magnitude and phase of the measured response
// with its +-2 sigma_total band, and the model, normalised by the DC gain) and stage_residual.png
// (|measured - model| against 2 sigma_total and sigma_noise).

#include <complex>
#include <string>
#include <vector>

#include "ident/frequency_response.hpp"
#include "ident/stage_fit.hpp"
#include "identify_args.hpp"
#include "log_experiments.hpp"

namespace hystloop {

// The stage's roots in LinearStageSpec's form: Hz, conjugate pairs once (imaginary part > 0),
// real roots as [re, 0]; by increasing magnitude.
std::vector<std::complex<double>> roots_hz_once(const std::vector<std::complex<double>>& roots_rad_s);

// Reads, fits, prints and writes (args.out); the exit code of run_identify.
int identify_stage(const IdentifyArgs& args, const ExperimentLogOptions& log_options);

}  // namespace hystloop
