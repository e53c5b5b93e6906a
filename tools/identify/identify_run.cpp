// hystloop-identify's work once its options are checked (identify_args.hpp): read the inputs
// (CSV or LCM logs), fit the chosen model, print it, write the YAML snippet and the plots
// (identify_output.hpp), publish the set and wait for its adoption (params_publish.hpp).
#include "identify_run.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/cli.hpp"
#include "core/clock.hpp"
#include "core/errors.hpp"
#include "fit_curves.hpp"
#include "fit_progress.hpp"
#include "ident/banning_fit.hpp"
#include "ident/fit_checks.hpp"
#include "ident/model_selection.hpp"
#include "ident/params_yaml.hpp"
#include "models/model_descriptors.hpp"
#include "ident/sample_csv.hpp"
#include "identify_output.hpp"
#include "identify_stage.hpp"
#include "lcm/message_checks.hpp"
#include "lcm/rig_auth.hpp"
#include "log_experiments.hpp"
#include "log_samples.hpp"
#include "params_publish.hpp"
#include "sample_budget.hpp"

namespace hystloop {
namespace {

// ident has no LCM: its sanity bounds are its own constants, kept equal to the contract's here.
static_assert(kFitMaxAbsVoltage_V == kMaxAbsVoltage_V && kFitMaxAbsPosition_m == kMaxAbsPosition_m,
              "ident/fit_checks.hpp and lcm/message_checks.hpp disagree on the sanity bounds");

// Set by run_identify: reports the stage in progress on stderr (silent unless wanted).
FitProgress* g_progress = nullptr;

// Reports `label` as running until the scope ends.
class ProgressStage {
 public:
  explicit ProgressStage(std::string label) {
    if (g_progress != nullptr) g_progress->stage(std::move(label));
  }
  ~ProgressStage() {
    if (g_progress != nullptr) g_progress->done();
  }
  ProgressStage(const ProgressStage&) = delete;
  ProgressStage& operator=(const ProgressStage&) = delete;
};

std::string on_samples(const std::string& what, std::size_t n) {
  return what + " on " + std::to_string(n) + " samples";
}

int refuse(FitStatus status, const std::string& reason) {
  std::cerr << "hystloop-identify: no fit (" << to_string(status) << "): " << reason << "\n";
  return 1;
}

// One run's context: its options, where the results go, the link a set is published on.
struct Run {
  const IdentifyArgs& args;
  OutputTarget out;
  ParamsLink* link = nullptr;  // --publish
  std::string heading;         // of the plots: what was fitted
};

// What a successful fit hands on: the snippet, the set to publish, the plots.
struct Fitted {
  std::string yaml;
  std::optional<ModelParamSet> set;  // --publish on HX_MODEL
  std::optional<MemFitResult> mem;   // --model mem: --publish on HX_PARAMS
  FitFigures figures;
  std::optional<FitPlotInput> plots;
};

double window_of(const SampleTable& s, std::size_t end) {
  return end < 2 || s.t.size() < end ? 0.0 : s.t[end - 1] - s.t.front();
}

ModelSelectionOptions selection_options(const IdentifyArgs& args) {
  ModelSelectionOptions o;
  o.mem.form = args.form == "derivative" ? MemFitForm::derivative : MemFitForm::integrated;
  o.mem.noise_rms_m = args.noise_rms_m;
  o.mem.min_snr = args.min_snr;
  o.pi.operators = args.operators;
  o.katalenic.output_polynomial_degree = args.katalenic_degree;
  return o;
}

// The plots of one model fitted on the whole record; its held-out branch from the same model
// fitted on the record's first part (as --model auto ranks it), when the record allows one.
FitPlotInput single_model_plots(const Run& run, ModelKind kind, const SampleTable& s, FitCurve chosen) {
  FitPlotInput in;
  in.heading = run.heading;
  in.chosen = std::move(chosen);
  ModelSelectionOptions o = selection_options(run.args);
  o.candidates = {kind};
  ModelSelection sel;
  {
    const ProgressStage stage(
        on_samples("fitting " + std::string(to_string(kind)) + " again without the held-out branch", s.u.size()));
    sel = select_model(s.u, s.y, o);
  }
  std::vector<FitCurve> curves = ranked_curves(sel, s.u, s.y);
  if (curves.empty()) {
    const std::string why = !sel.reason.empty() ? sel.reason : sel.ranking.empty() ? "" : sel.ranking.front().reason;
    std::printf("plots: no held-out branch (%s)\n", why.c_str());
    return in;
  }
  std::printf("held out from t = %.4g s (sample %zu): %s fitted on the record before predicts it to %.4g nm RMS\n",
              s.t[sel.split_index], sel.split_index, std::string(to_string(kind)).c_str(),
              curves.front().heldout_rms_m * 1e9);
  in.heldout = std::move(curves.front());
  return in;
}

// Prints the set by its model's table ("mem: c1 5.3e-09 m/V, ...", as the services log a set) and
// keeps its YAML section.
template <class D>
void take_params(const typename D::Params& p, Fitted& out) {
  std::printf("%s: %s\n", std::string(D::name).c_str(), D::summary_of(p).c_str());
  out.yaml = to_yaml(p);
}

// The set `fit` holds for `kind`, printed and kept; 1 when its values make no valid set.
int take_set(const ModelSelection& fit, ModelKind kind, Fitted& out) {
  try {
    out.set = fitted_set(fit, kind);
  } catch (const ParameterError& e) {
    return refuse(FitStatus::out_of_range, e.what());
  }
  OnlineModels::visit(kind, [&]<class D>() { take_params<D>((*out.set).*D::in_set, out); });
  return 0;
}

// One model fitted on the whole record.
int fit_single(const Run& run, ModelKind kind, const SampleTable& s, Fitted& out) {
  ModelSelection fit;
  ModelScore r;
  {
    const ProgressStage stage(on_samples("fitting " + std::string(to_string(kind)), s.u.size()));
    r = fit_candidate(kind, s.u, s.y, selection_options(run.args), fit);
  }
  if (r.status != FitStatus::ok) return refuse(r.status, r.reason);
  if (const int rc = take_set(fit, kind, out)) return rc;
  std::printf("fit: residual %.4g nm RMS, %zu samples, %.1f ms", r.train_rms_m * 1e9, r.samples_used,
              r.fit_time_s * 1e3);
  if (kind == ModelKind::mem) {
    std::printf(", %s form, noise %.4g nm, %zu branches", run.args.form.c_str(), fit.mem.noise_rms_m * 1e9,
                fit.mem.branches_used);
    out.mem = fit.mem;
  } else if (kind == ModelKind::pi) {
    std::printf(", offset %.6g m", fit.pi.offset_m);  // PiParams has no offset: a PI model starts at 0
  }
  std::printf("\n");
  out.figures = {r.train_rms_m, std::nan(""), r.samples_used, window_of(s, s.t.size())};
  if (run.out.plots_dir) out.plots = single_model_plots(run, kind, s, whole_record_curve(fit, kind, s.u, s.y));
  return 0;
}

// Every model of the set fitted and ranked on held-out data; the best one emitted.
int fit_auto(const Run& run, const SampleTable& s, Fitted& out) {
  const ModelSelectionOptions o = selection_options(run.args);
  ModelSelection sel;
  {
    const ProgressStage stage(on_samples("fitting and ranking every model (auto)", s.u.size()));
    sel = select_model(s.u, s.y, o);
  }
  std::printf("rank  model       status           train [nm]  held-out [nm]  fit [ms]\n");
  for (std::size_t i = 0; i < sel.ranking.size(); ++i) {
    const auto& r = sel.ranking[i];
    std::printf("%4zu  %-10s  %-15s  %10.4g  %13.4g  %8.1f%s%s\n", i + 1, std::string(to_string(r.kind)).c_str(),
                std::string(to_string(r.status)).c_str(), r.train_rms_m * 1e9, r.holdout_rms_m * 1e9,
                r.fit_time_s * 1e3, r.reason.empty() ? "" : "  ", r.reason.c_str());
  }
  if (!sel.ok()) return refuse(sel.status, sel.reason);
  const ModelScore& best = sel.ranking.front();
  std::printf("held out from sample %zu of %zu; best: %s\n", sel.split_index, s.u.size(),
              std::string(to_string(best.kind)).c_str());
  if (const int rc = take_set(sel, best.kind, out)) return rc;
  out.figures = {best.train_rms_m, best.holdout_rms_m, best.samples_used, window_of(s, sel.split_index + 1)};
  if (run.out.plots_dir) {
    FitPlotInput in;
    in.heading = run.heading;
    in.candidates = ranked_curves(sel, s.u, s.y);
    in.chosen = in.candidates.front();
    out.plots = std::move(in);
  }
  return 0;
}

std::int32_t version_to_publish(ParamsLink& link, const IdentifyArgs& args) {
  if (args.link.version) return *args.link.version;
  const std::int32_t heard = link.highest_version_heard();
  if (heard > 0) {
    std::printf("version in use on %s: %d\n", link.channels().prefix.c_str(), heard);
  } else {
    std::printf("no parameter version heard on %s/%s/%s in %.2g s\n", link.channels().params.c_str(),
                link.channels().model.c_str(), link.channels().command.c_str(), args.link.listen_s);
  }
  return next_params_version(heard);
}

// Publishes the set (HX_PARAMS for a MEM set unless --publish-on model, else HX_MODEL), then
// waits for the compensator to adopt it unless --no-wait.
int publish_fitted(ParamsLink& link, const IdentifyArgs& args, const Fitted& f) {
  const std::int32_t version = version_to_publish(link, args);
  int sent = 0;
  std::string channel, what, source;
  if (args.publish_on_params && f.mem) {
    const mem_params_t msg = to_mem_params(*f.mem, f.figures.window_s, version, wall_utime(), identify_source());
    sent = link.publish(msg);
    channel = link.channels().params, what = "MEM", source = msg.source;
  } else {
    try {
      f.set->validate();
    } catch (const ParameterError& e) {
      std::cerr << "hystloop-identify: the set was not published: " << e.what() << "\n";
      return kExitFailure;
    }
    const model_params_t msg = to_model_params(*f.set, f.figures, version, wall_utime(), identify_source());
    sent = link.publish(msg);
    channel = link.channels().model, what = std::string(to_string(f.set->kind));
    source = msg.source;
  }
  if (sent == 0) {
    std::cerr << "hystloop-identify: the parameters were not published (refused by the message contract check "
                 "or by LCM)\n";
    return kExitFailure;
  }
  std::printf("published %s parameters v%d on %s (%d time(s)) via %s, source '%s'\n", what.c_str(), version,
              channel.c_str(), sent, link.url().c_str(), source.c_str());
  if (args.no_wait) return 0;
  std::fflush(stdout);
  const ParamsLink::Adoption a = link.wait_for_adoption(version);
  if (a.adopted) {
    std::printf("%s\n", a.verdict.c_str());
    return 0;
  }
  std::cerr << "hystloop-identify: " << a.verdict << "\n";
  return kExitFailure;
}

// The common end of every fit: the snippet, the plots, the publishing.
int finish(const Run& run, const SampleTable& s, const Fitted& f) {
  if (const int rc = write_yaml(run.out, f.yaml)) return rc;
  if (f.plots) {
    if (const int rc = write_plots(run.out, s, *f.plots, run.args.gnuplot)) return rc;
  }
  if (run.link == nullptr) return 0;
  return publish_fitted(*run.link, run.args, f);
}

int fit_banning_and_emit(const IdentifyArgs& args, const std::vector<BanningExperimentData>& data) {
  BanningFitResult r;
  {
    const ProgressStage stage("fitting banning on " + std::to_string(data.size()) + " experiments");
    r = fit_banning(data);
  }
  std::printf("experiment  offset [V]  amplitude [V]  frequency [Hz]  kind       feature\n");
  for (std::size_t i = 0; i < r.points.size(); ++i) {
    const auto& p = r.points[i];
    if (!p.used) {
      std::printf("%10zu  skipped: %s\n", i, p.note.c_str());
      continue;
    }
    std::printf("%10zu  %10.3f  %13.3f  %14.3f  ", i, p.offset_V, p.amplitude_V, p.frequency_Hz);
    if (p.magnitude_experiment && r.stage_identified) {
      std::printf("magnitude  h = %.5g", p.magnitude);
    } else if (p.magnitude_experiment) {  // h needs the stage fit: the first harmonic of y as measured
      std::printf("magnitude  y1 = %.5g nm", p.response_m * 1e9);
    } else {
      std::printf("loop       centre %.5g nm, slope %.5g nm/V, area %.5g nm V", p.features.y_centre * 1e9,
                  p.features.slope * 1e9, p.features.area * 1e9);
      if (p.area_fitted && p.lag_area != 0.0) std::printf(" %+.3g for the lag", p.lag_area * 1e9);
    }
    std::printf("\n");
  }
  if (!r.ok()) return refuse(r.status, r.reason);
  std::printf("Banning: a = %.6g m/V, b = %.6g m/V, alpha = %.6g 1/V\n", r.hysteresis.a, r.hysteresis.b,
              r.hysteresis.alpha);
  if (r.stage_identified) {
    std::printf("         k = %.6g 1/s^2, c = %.6g 1/s (f_n = %.1f Hz, zeta = %.4f)\n", r.stage.k, r.stage.c,
                r.stage.natural_frequency() / (2.0 * 3.141592653589793), r.stage.damping_ratio());
  } else {
    std::printf("         stage not identified: %s\n", r.reason.c_str());
  }
  std::printf("fit: centre line %.4g nm RMS, slopes %.3g %% RMS, areas %.3g %% RMS, magnitudes %.3g %% RMS, %.1f ms\n",
              r.centre_rms_m * 1e9, r.slope_rel_rms * 100.0, r.area_rel_rms * 100.0, r.magnitude_rel_rms * 100.0,
              r.solve_time_s * 1e3);
  if (r.lag_identified) {
    double lo = 1e300, hi = -1e300;
    for (const auto& p : r.points) {
      if (!p.area_fitted || !(p.features.area > 0.0)) continue;
      lo = std::min(lo, p.lag_area / p.features.area), hi = std::max(hi, p.lag_area / p.features.area);
    }
    std::printf(
        "lag: %.3g us beyond the stage model (phases of %zu magnitude experiments below f_n/2, %.2g mrad RMS); "
        "the areas alpha is fitted to corrected by %+.2g .. %+.2g %%\n",
        r.delay_s * 1e6, r.lag_experiments, r.lag_phase_rms_rad * 1e3, lo * 100.0, hi * 100.0);
  } else if (!r.lag_note.empty()) {
    std::printf("lag: %s\n", r.lag_note.c_str());
  }
  const OutputTarget out = output_target(args.out);
  if (out.plots_dir) {
    std::printf("plots: none for banning (its fit is on loop features of several experiments, not one record)\n");
  }
  return write_yaml(out, to_yaml(r.hysteresis, r.stage_identified ? &r.stage : nullptr));
}

int fit_banning_files(const IdentifyArgs& args, const std::vector<SampleTable>& tables) {
  std::vector<SampleTable> groups;
  for (const auto& t : tables) {
    for (auto& g : split_experiments(t)) groups.push_back(std::move(g));
  }
  std::vector<BanningExperimentData> data;
  for (const auto& g : groups) {
    const double fs = sample_rate_Hz(g.t);
    if (!(fs > 0.0)) return refuse(FitStatus::size_mismatch, "an experiment's t does not increase: no sample rate");
    data.push_back({g.u, g.y, fs});
  }
  return fit_banning_and_emit(args, data);
}

ExperimentLogOptions experiment_options(const IdentifyArgs& args) {
  ExperimentLogOptions o;
  o.control_channel = channel_name(args.link.rig, kControlSuffix);
  o.command_channel = channel_name(args.link.rig, kCommandSuffix);
  o.sensor_channel = channel_name(args.link.rig, kSensorSuffix);
  o.compensator_process = args.link.compensator;
  o.dt_s = args.dt_s;
  o.max_not_as_commanded = args.max_late;
  o.max_missing = args.max_missing;
  o.rate_independent_below_Hz = BanningFitOptions{}.frequency_threshold_Hz;
  o.axis = args.axis;
  return o;
}

LoggedExperiments read_experiments(const IdentifyArgs& args) {
  LoggedExperiments logged = read_logged_experiments(args.files, experiment_options(args));
  std::cout << describe(logged);
  return logged;
}

// The experiments the loop ran that the log lists, when it holds at least `min_requests` requests
// (the cheap look first) and one of them ran; none otherwise (the record is fitted as it is).
LoggedExperiments experiments_in_log(const IdentifyArgs& args, std::size_t min_requests) {
  const ExperimentLogOptions o = experiment_options(args);
  if (count_experiment_requests(args.files, o) < min_requests) return {};
  try {
    return read_logged_experiments(args.files, o);
  } catch (const SampleLogError&) {
    return {};
  }
}

// A log whose record holds several experiments, none chosen: one fit over all of them mixes
// loops of different amplitudes and offsets (and the settling between) into a model that fits
// none (on the demo's log MEM's c3 lands on its search bound). Lists them and says how to pick.
void throw_if_several_experiments(const IdentifyArgs& args) {
  const LoggedExperiments logged = experiments_in_log(args, 2);
  const std::size_t n = logged.experiments.size();
  if (n < 2) return;
  const std::string where = args.files.size() == 1 ? args.files.front() : "the log";
  throw std::runtime_error(where + " holds " + std::to_string(n) +
                           " experiments the loop ran; fit one with --experiment N (N as listed), or a time range "
                           "with --from S --to S (--model banning fits a series of them):\n" +
                           list_experiments(logged, experiment_options(args)));
}

// A fit of a whole log that holds an experiment the loop ran (several are refused before the
// fit: throw_if_several_experiments): the record mixes it with whatever else ran (tracking,
// settling), which is rarely one model's data (the demo's log: one identification experiment,
// then tracking, fails on MEM's c3 bound). Says so after the fit, failed or not, and lists it.
void note_experiments_in_whole_log(const IdentifyArgs& args) {
  if (!args.from_logs || args.experiment || args.from_s || args.to_s) return;
  const LoggedExperiments logged = experiments_in_log(args, 1);
  if (logged.experiments.empty()) return;
  std::cerr << "hystloop-identify: note: this fit is over the whole record, and the log holds "
            << logged.experiments.size()
            << " experiment(s) the loop ran; fit one alone with --experiment N (N as listed), or a time range with "
               "--from S --to S:\n"
            << list_experiments(logged, experiment_options(args));
}

// Reads every input file: all CSV, or all LCM logs (one record). Throws CsvError /
// SampleLogError, or std::runtime_error for a CSV over the sample budget.
std::vector<SampleTable> read_inputs(const IdentifyArgs& args, bool logs) {
  const ProgressStage stage("reading " + std::to_string(args.files.size()) + " file(s)");
  std::vector<SampleTable> tables;
  if (!logs) {
    // Counted first: an oversized CSV is refused before it takes memory.
    std::size_t rows = 0;
    for (const auto& f : args.files) rows += count_csv_rows(f);
    if (auto why = over_sample_budget((rows + args.decimate - 1) / args.decimate, args.max_samples, args.decimate)) {
      throw std::runtime_error(*why);
    }
    for (const auto& f : args.files) tables.push_back(read_sample_csv(f));
    return tables;
  }
  LogReadOptions o;
  o.sensor_channel = channel_name(args.link.rig, kSensorSuffix);
  o.time_base = args.time_from == "utime" ? LogTimeBase::utime : LogTimeBase::seq;
  o.dt_s = args.dt_s;
  o.from_s = args.from_s;
  o.to_s = args.to_s;
  o.axis = args.axis;
  if (args.experiment) {
    // One experiment the loop ran (e.g. hystloop-ctl experiment --mem-paper), as listed.
    LoggedExperiments logged = read_experiments(args);
    if (*args.experiment >= logged.experiments.size()) {
      throw SampleLogError("--experiment " + std::to_string(*args.experiment) + ": the log holds " +
                           std::to_string(logged.experiments.size()) + " experiment(s), numbered from 0");
    }
    LoggedExperiment& e = logged.experiments[*args.experiment];
    // Late commands and skipped ticks do not spoil a rate-independent fit; these do.
    std::string why;
    if (!e.complete) why = e.problem;
    if (e.safe_state > 0)
      why = std::to_string(e.safe_state) + " sample(s) in the safe state (watchdog trip or disarmed)";
    if (e.sensor_fault > 0) why = std::to_string(e.sensor_fault) + " sample(s) flagged SENSOR_FAULT";
    if (!why.empty())
      throw SampleLogError("--experiment " + std::to_string(*args.experiment) + " cannot be used: " + why);
    std::cout << "fitting experiment " << *args.experiment << ": " << e.samples.t.size()
              << " samples (for this rate-independent fit, late commands and skipped ticks do no harm)\n";
    tables.push_back(std::move(e.samples));
    return tables;
  }
  if (!args.from_s && !args.to_s) throw_if_several_experiments(args);
  LogSamples samples = read_sample_logs(args.files, o);
  std::cout << describe(samples, o);
  tables.push_back(std::move(samples.table));
  return tables;
}

// --model banning on logs: the experiments the live loop ran (hystloop-ctl experiment
// --banning-series), one table per measured experiment that can be used.
int fit_banning_logs(const IdentifyArgs& args) {
  const LoggedExperiments logged = read_experiments(args);
  std::vector<BanningExperimentData> data;
  for (const auto& e : logged.experiments) {
    // The requested frequency is known: no need to estimate it from a u with held samples.
    if (!e.spec.settle && e.usable()) data.push_back({e.samples.u, e.samples.y, 1.0 / args.dt_s, e.spec.frequency_hz});
  }
  if (data.empty()) {
    return refuse(FitStatus::too_few_samples, "no usable measured experiment in the log (see the list above)");
  }
  return fit_banning_and_emit(args, data);
}

int usage_error(const std::string& message) {
  std::cerr << "hystloop-identify: " << message << "\n";
  return kExitUsage;
}

std::string heading_of(const IdentifyArgs& args) {
  std::string h = std::filesystem::path(args.files.front()).filename().string();
  if (args.files.size() > 1) h += " + " + std::to_string(args.files.size() - 1) + " more";
  if (args.experiment) h += ", experiment " + std::to_string(*args.experiment);
  if (args.from_s || args.to_s) {
    h += ", t in [" + (args.from_s ? std::to_string(*args.from_s) : std::string("start")) + ", " +
         (args.to_s ? std::to_string(*args.to_s) : std::string("end")) + ") s";
  }
  return h;
}

int fit_inputs(const IdentifyArgs& args) {
  if (args.choice.mode == ModelChoice::Mode::stage) {
    validate_rig_prefix(args.link.rig);
    return identify_stage(args, experiment_options(args));
  }
  std::unique_ptr<ParamsLink> link;
  // The key signs a published set and verifies the logs read (for_each_log_event).
  if (!args.key_file.empty()) set_process_rig_auth(rig_auth_from_key_file(args.key_file, "--key-file"));
  if (args.publish) {
    PublishOptions p = args.link;
    if (args.timeout_s) p.timeout_s = *args.timeout_s;
    p.axis = args.axis;                      // the set models the axis the samples were of
    link = std::make_unique<ParamsLink>(p);  // before the fit: a refused URL or no route fails fast
  } else {
    validate_rig_prefix(args.link.rig);
  }
  if (args.from_logs && args.choice.mode == ModelChoice::Mode::banning) return fit_banning_logs(args);
  std::vector<SampleTable> tables = read_inputs(args, args.from_logs);
  // The budget counts every K-th sample (what --decimate promises), not the turning points kept
  // beside them: a few per reversal.
  std::size_t samples = 0;
  const bool rate_independent = args.choice.mode != ModelChoice::Mode::banning;
  for (auto& t : tables) {
    samples += (t.u.size() + args.decimate - 1) / args.decimate;
    decimate(t, args.decimate, rate_independent);
  }
  if (auto why = over_sample_budget(samples, args.max_samples, args.decimate)) return usage_error(*why);
  if (args.choice.mode == ModelChoice::Mode::banning) return fit_banning_files(args, tables);
  const Run run{args, output_target(args.out), link.get(), heading_of(args)};
  Fitted fitted;
  const SampleTable& record = tables.front();
  const int rc = args.choice.mode == ModelChoice::Mode::automatic ? fit_auto(run, record, fitted)
                                                                  : fit_single(run, args.choice.kind, record, fitted);
  note_experiments_in_whole_log(args);
  if (rc != 0) {
    if (link != nullptr) std::cerr << "hystloop-identify: nothing published\n";
    return rc;
  }
  return finish(run, record, fitted);
}

}  // namespace

int run_identify(const IdentifyArgs& args) {
  FitProgress progress(progress_wanted(args.progress) ? stderr : nullptr,
                       std::chrono::milliseconds(static_cast<long>(args.progress_period_s * 1e3)));
  g_progress = &progress;
  struct Reset {
    ~Reset() { g_progress = nullptr; }
  } reset;
  try {
    return fit_inputs(args);
  } catch (const std::runtime_error& e) {  // CsvError, SampleLogError, the budget, several experiments, LCM setup
    return usage_error(e.what());
  } catch (const ParameterError& e) {
    return usage_error(e.what());
  }
}

}  // namespace hystloop
