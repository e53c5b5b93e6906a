#include "identify_args.hpp"

#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "core/cli.hpp"
#include "core/errors.hpp"
#include "log_samples.hpp"
#include "models/model_descriptors.hpp"

namespace hystloop {

std::optional<ModelChoice> parse_model_choice(const std::string& name) {
  ModelChoice c;
  c.name = name;
  if (name == "auto") return c;
  if (name == "stage") {
    c.mode = ModelChoice::Mode::stage;
    return c;
  }
  if (name == BanningDescriptor::name) {
    c.mode = ModelChoice::Mode::banning;
    return c;
  }
  const std::optional<ModelKind> kind = parse_model_kind(name);
  if (!kind) return std::nullopt;
  c.mode = ModelChoice::Mode::single;
  c.kind = *kind;
  return c;
}

std::string model_choices() {
  std::vector<std::string_view> names = model_kind_names();
  names.push_back(BanningDescriptor::name);
  names.emplace_back("stage");
  names.emplace_back("auto");
  return choice_list(names);
}

void add_identify_options(CLI::App& app, IdentifyArgs& args) {
  app.add_option("files", args.files,
                 "CSV file(s) (for banning one per experiment, or one with an 'experiment' column), or LCM log file(s)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--model", args.model,
                 model_choices() +
                     " (auto: fit all, rank on held-out data; stage: the linear stage's dynamics "
                     "from a multisine experiment: FRF, poles, zeros, delay)")
      ->check([](const std::string& v) { return parse_model_choice(v) ? std::string() : "unknown model '" + v + "'"; })
      ->capture_default_str();
  app.add_option("--form", args.form, "MEM data form: integrated branches or the paper's derivative")
      ->check(CLI::IsMember({"integrated", "derivative"}))
      ->capture_default_str();
  app.add_option("--out", args.out,
                 "write the YAML config snippet to this file; or, given a folder (one that exists, or a name ending "
                 "in '/'), write config.yaml there with the plots of the fit: loop_u_y.png (measured and model "
                 "loops, u -> y), residual.png (measured - model against time), heldout_u_y.png (the held-out "
                 "branch, predicted by the model fitted without it), candidates.png (--model auto: every model "
                 "side by side), their data (fit_<model>.dat, heldout_<model>.dat: t, u, y measured, y model, "
                 "residual, held out) and plots.gp to re-run gnuplot there");
  app.add_option("--gnuplot", args.gnuplot, "gnuplot executable for the plots of --out DIR")->capture_default_str();
  app.add_option("--noise-rms-m", args.noise_rms_m, "sensor noise RMS [m]; 0 = estimate from the data")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--min-snr", args.min_snr, "MEM derivative form: keep points with at least this SNR")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--operators", args.operators, "PI: number of play operators")
      ->check(CLI::Range(1, 32))
      ->capture_default_str();
  app.add_option("--katalenic-degree", args.katalenic_degree,
                 "Katalenic: output shaping polynomial degree (1 = linear)")
      ->check(CLI::Range(1, 7))
      ->capture_default_str();
  auto* logs = app.add_option_group("LCM logs", "reading HX_SENSOR from LCM event logs");
  logs->add_flag("--log", args.log,
                 "read the files as LCM event logs whatever their names (default: by the .lcmlog ending)");
  logs->add_option("--rig", args.link.rig,
                   "rig channel prefix: samples from <rig>SENSOR; --publish to <rig>MODEL or <rig>PARAMS")
      ->capture_default_str();
  logs->add_option("--dt", args.dt_s, "tick period [s]: t = (seq - first seq) * dt")->capture_default_str();
  logs->add_option("--time-from", args.time_from, "time base: seq (* --dt) or utime (the samples' timestamps)")
      ->check(CLI::IsMember({"seq", "utime"}))
      ->capture_default_str();
  logs->add_option("--from", args.from_s, "fit only samples at t >= this [s after the record's first sample]");
  logs->add_option("--to", args.to_s, "fit only samples at t < this [s after the record's first sample]");
  add_axis_option(logs, "--axis", args.axis,
                  "which axis of a stage of several to identify (default x; the blocks carry every axis; a "
                  "one-axis log has x only)");
  logs->add_option("--experiment", args.experiment,
                   "fit only this experiment the loop ran (numbered from 0 as listed; e.g. the one hystloop-ctl "
                   "experiment --mem-paper ran). A log with several experiments needs it (or --from/--to): "
                   "without, they are listed and the exit status is 2");
  logs->add_option("--compensator", args.link.compensator,
                   "process name of the compensator: whose HX_CONTROL experiment requests count, and whose "
                   "HX_STATUS says whether a published set was adopted")
      ->capture_default_str();
  logs->add_option("--max-late", args.max_late,
                   "banning: skip a frequency-response experiment if more than this fraction of its samples were "
                   "not applied as commanded (late, saturated, slew-limited); hysteresis loops keep them")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  logs->add_option("--max-missing", args.max_missing,
                   "banning: skip a hysteresis-loop experiment if more than this fraction of its ticks has no sample "
                   "(a frequency-response experiment may miss none)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  auto* stage = app.add_option_group("stage",
                                     "--model stage: the multisine's record (CSV t,u,y or u,y; or a log's "
                                     "multisine experiment, which gives its layout)");
  stage->add_option("--sample-rate", args.sample_rate_Hz, "sample rate [Hz] (default: from t; required for a u,y CSV)")
      ->check(CLI::PositiveNumber);
  stage->add_option("--period-samples", args.period_samples, "samples per period N (a CSV: required)");
  stage->add_option("--periods", args.periods, "periods per realisation P (a CSV: required)");
  stage->add_option("--realisations", args.realisations, "realisations R (a CSV: default 1)");
  stage->add_option("--transient-periods", args.transient_periods, "periods dropped per realisation")
      ->capture_default_str();
  stage->add_option("--skip", args.skip_samples, "CSV: samples before the record (e.g. a fade-in)")
      ->capture_default_str();
  stage->add_option("--band", args.band, "F_MIN:F_MAX [Hz]: the excited lines (default: those u excites)");
  stage->add_flag("--odd-lines", args.odd_lines, "with --band: odd lines only");
  stage
      ->add_option("--order", args.order,
                   "NUM/DEN (numerator/denominator order, e.g. 2/4), or auto: the lowest denominator order "
                   "whose chi-square per line the uncertainty explains")
      ->capture_default_str();
  stage->add_option("--max-order", args.max_order, "auto: largest denominator order tried")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  stage->add_option("--max-delay", args.max_delay_s, "largest input delay searched [s]")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  stage
      ->add_option("--hysteresis-plays", args.hysteresis_plays,
                   "play operators of a Prandtl-Ishlinskii hysteresis fitted together with the stage, so that the "
                   "series model explains the record and the stage is measured from the hysteresis' output, not "
                   "from u (whose best linear approximation rises with frequency); 0: from u -> y alone")
      ->check(CLI::Range(0, 32))
      ->capture_default_str();
  stage->add_flag("--continuous", args.continuous,
                  "the record was not held and sampled at the sample rate: fit the continuous response (default: "
                  "the exact zero-order-hold response, as a bridge drives and samples)");
  stage
      ->add_option("--sample-at", args.sample_at,
                   "end: y_k is the position at the end of tick k, after u_k was held over it (the rig's "
                   "convention, models/linear_stage.hpp: the delay written is the compensator's); start: y_k was "
                   "sampled as u_k was applied (a conventional DAQ)")
      ->check(CLI::IsMember({"end", "start"}))
      ->capture_default_str();
  auto* true_stage =
      stage
          ->add_option(
              "--true-stage", args.true_stage,
              "a simulated record: the YAML whose plant.stage (the bridge's series plant) or stage section is "
              "the stage it came from; prints the model's error against it in dB and degrees up to "
              "--compare-to, and at how many lines it lies inside the measured +-2 sigma band (after the model "
              "and plots are written; exit 2 when the file holds no linear stage)")
          ->check(CLI::ExistingFile);
  stage->add_option("--compare-to", args.compare_to_Hz, "with --true-stage: the highest frequency compared [Hz]")
      ->check(CLI::PositiveNumber)
      ->needs(true_stage)
      ->capture_default_str();
  auto* pub = app.add_option_group("publishing", "sending the fitted set to a running compensator");
  pub->add_flag("--publish", args.publish,
                "after a successful fit, publish the set (3 times, 10 ms apart): any model as model_params_t on "
                "<rig>MODEL (the compensator switches to it at its next reversal); --model mem as mem_params_t on "
                "<rig>PARAMS (see --publish-on); then wait until the compensator uses it (--timeout, --no-wait)");
  pub->add_option("--publish-on", args.publish_on,
                  "params: MEM parameters on <rig>PARAMS, the compensator's mode unchanged (default for --model mem); "
                  "model: <rig>MODEL, the feedforward switches to the model (default for the others)")
      ->check(CLI::IsMember({"params", "model"}));
  pub->add_option("--timeout", args.timeout_s,
                  "after publishing, wait at most this long for the compensator (--compensator) to report the "
                  "set's version in use [s] (default 5); exit 1 if it does not")
      ->check(CLI::Range(0.0, 600.0));
  pub->add_flag("--no-wait", args.no_wait, "publish and exit 0 without waiting for the set to be adopted");
  pub->add_option("--version", args.link.version,
                  "parameter set version (default: 1 + the highest heard on <rig>PARAMS / <rig>COMMAND, at least 2)");
  pub->add_option("--listen-s", args.link.listen_s, "how long to listen for the version in use [s]")
      ->capture_default_str();
  pub->add_option("--lcm-url", args.link.lcm_url, "LCM URL (default: $LCM_DEFAULT_URL, else udpm with ttl=0)");
  pub->add_flag("--allow-network", args.link.allow_network,
                "allow an LCM URL whose packets leave this host (ttl > 0, tcpq)");
  pub->add_option("--key-file", args.key_file,
                  "the rig key (auth.key_file of the services): sign the published set; verify the logs read (what "
                  "fails its signature is left out and counted)");
  auto* bounds = app.add_option_group("bounds", "memory and progress of long fits");
  bounds
      ->add_option("--max-samples", args.max_samples,
                   "refuse more samples than this (after --decimate): the fit holds its problem in memory, "
                   "~150 (mem) to ~300 (auto) bytes per sample")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  bounds
      ->add_option("--decimate", args.decimate,
                   "keep every K-th sample and, but for banning, the input's turning points between them "
                   "(rate-independent models lose little; --max-samples counts the K-th samples, the turns come "
                   "on top: a few per reversal of a slow record)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  bounds->add_flag("--progress", args.progress,
                   "print the running stage and its elapsed time to stderr every 2 s (default: when stderr is a "
                   "terminal)");
  bounds->add_option("--progress-period-s", args.progress_period_s, "period of the progress lines [s]")
      ->check(CLI::Range(0.001, 3600.0))
      ->capture_default_str();
}

std::optional<std::string> check_identify_args(IdentifyArgs& args) {
  const std::optional<ModelChoice> choice = parse_model_choice(args.model);
  if (!choice) return "--model " + args.model + ": unknown";
  args.choice = *choice;
  std::size_t log_names = 0;
  for (const auto& f : args.files) log_names += looks_like_lcm_log(f) ? 1 : 0;
  args.from_logs = args.log || log_names == args.files.size();
  const bool range = args.from_s || args.to_s;
  const bool banning = args.choice.mode == ModelChoice::Mode::banning;
  if (!args.from_logs && log_names > 0) return "mixed inputs: give either CSV files or LCM logs (*.lcmlog)";
  if (!args.from_logs && range) return "--from/--to select a range of an LCM log";
  if (!args.from_logs && args.experiment) return "--experiment selects an experiment of an LCM log";
  const bool mem = args.choice.mode == ModelChoice::Mode::single && args.choice.kind == ModelKind::mem;
  if (args.choice.mode == ModelChoice::Mode::stage) {
    if (args.publish) return "--publish: a stage model goes into the compensator's config (write it with --out)";
    if (args.files.size() != 1 && !args.from_logs) return "--model stage takes one CSV file";
    if (range) return "--from/--to: --model stage reads the whole multisine record (--skip for a CSV)";
  }
  if (args.publish && banning) {
    return "--publish: Banning's model is identified offline only and has no kind on HX_MODEL; write it with --out "
           "and give it to the compensator's config (--params)";
  }
  if (!args.publish_on.empty() && !args.publish) return "--publish-on " + args.publish_on + ": only with --publish";
  if (args.publish_on == "params" && !mem) {
    return "--publish-on params sends MEM parameters (mem_params_t on HX_PARAMS): only with --model mem (got --model " +
           args.model + ")";
  }
  args.publish_on_params = mem && args.publish_on != "model";
  if ((args.timeout_s || args.no_wait) && !args.publish) {
    return std::string(args.no_wait ? "--no-wait" : "--timeout") + ": only with --publish";
  }
  if (args.timeout_s && args.no_wait) return "--timeout and --no-wait: choose one";
  if (args.experiment && range) return "--experiment selects its own samples: not with --from/--to";
  if (args.from_logs && banning && range) {
    return "--from/--to do not apply to --model banning on logs: the experiments are found by their requests "
           "(HX_CONTROL) and commands";
  }
  if (!banning && !args.from_logs && args.files.size() != 1) {
    return "--model " + args.model + " takes one file (got " + std::to_string(args.files.size()) + ")";
  }
  return std::nullopt;
}

}  // namespace hystloop
