#pragma once
// hystloop-identify's command line: the options (add_identify_options), and every check of
// their combination in one place (check_identify_args), made before any file is read.

#include <CLI/CLI.hpp>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "models/model_set.hpp"
#include "params_publish.hpp"
#include "sample_budget.hpp"

namespace hystloop {

// What --model asks for: one model of the set (ModelKind), the Banning recipe (several
// experiments, not a ModelKind), or every model of the set ranked on held-out data.
struct ModelChoice {
  enum class Mode { single, banning, automatic, stage };
  Mode mode = Mode::automatic;
  ModelKind kind = ModelKind::mem;  // when mode == single
  std::string name = "auto";        // as given
};
// An online model's name (parse_model_kind), "banning", "stage" (the linear stage's dynamics from a
// multisine, identify_stage.hpp) or "auto"; nullopt otherwise.
std::optional<ModelChoice> parse_model_choice(const std::string& name);
// "mem, pi, katalenic, linear, banning, stage or auto": what parse_model_choice accepts, from the registry.
std::string model_choices();

struct IdentifyArgs {
  std::vector<std::string> files;
  std::string model = "auto";
  ModelChoice choice{};  // from `model`, by check_identify_args
  std::string form = "integrated";
  std::string out;  // the YAML file, or a folder for config.yaml and the plots (identify_output.hpp)
  std::string gnuplot = "gnuplot";
  double noise_rms_m = 0.0;
  double min_snr = 3.0;
  std::size_t operators = 15;
  int katalenic_degree = 1;
  // LCM logs
  bool log = false;
  bool from_logs = false;  // by check_identify_args: --log, or every file named *.lcmlog
  double dt_s = 1e-4;
  std::string time_from = "seq";
  std::optional<double> from_s, to_s;
  std::optional<std::size_t> experiment;
  int axis = 0;  // --axis x|y|z: whose samples (and experiments) of a log of several axes
  double max_late = 0.02;
  double max_missing = 0.01;
  // --publish; its rig prefix and compensator name also say whose channels a log is read from
  bool publish = false;
  PublishOptions link{};
  std::string key_file;             // the rig key: sign the set (README "Authenticated rig")
  std::string publish_on;           // "params" (MEM on HX_PARAMS) or "model" (HX_MODEL); empty: by the model
  bool publish_on_params = false;   // by check_identify_args
  std::optional<double> timeout_s;  // link.timeout_s when given
  bool no_wait = false;
  // --model stage (identify_stage.hpp): the multisine's layout, given or from the log's experiment
  std::optional<double> sample_rate_Hz;  // default: from the CSV's t, or 1 / --dt for a log
  std::size_t period_samples = 0;        // N; 0: from the log's experiment
  std::size_t periods = 0;               // P per realisation
  std::size_t realisations = 0;          // R
  std::size_t transient_periods = 1;     // dropped at the start of each realisation
  std::size_t skip_samples = 0;          // CSV: samples before the record (a ramp)
  std::string band;                      // F_MIN:F_MAX [Hz]; empty: the lines u excites
  bool odd_lines = false;                // with --band: odd lines only
  std::string order = "auto";            // NUM/DEN (e.g. 2/4), or auto
  int max_order = 8;                     // auto: largest denominator order tried
  double max_delay_s = 1e-3;
  // Play operators of the hysteresis fitted with the stage (ident/stage_hysteresis_fit.hpp); 0: the
  // stage from u -> y alone (the best linear approximation of hysteresis and stage together).
  std::size_t hysteresis_plays = 15;
  bool continuous = false;        // the data were not held and sampled at the sample rate (no ZOH in the model)
  std::string sample_at = "end";  // y_k measured at the end of tick k (the rig's, linear_stage.hpp) or its start
  std::string true_stage;         // a YAML whose plant.stage (or stage) is the stage the record came from
  double compare_to_Hz = 3000.0;  // the model held against it up to this frequency
  // bounds
  std::size_t max_samples = kDefaultMaxSamples;
  std::size_t decimate = 1;
  bool progress = false;
  double progress_period_s = 2.0;
};

void add_identify_options(CLI::App& app, IdentifyArgs& args);

// The combinations CLI11 cannot check (mixed inputs, log-only options on a CSV, --publish of
// Banning's model, ...). Fills args.choice, args.from_logs and args.publish_on_params; returns
// the reason for a usage error.
std::optional<std::string> check_identify_args(IdentifyArgs& args);

}  // namespace hystloop
