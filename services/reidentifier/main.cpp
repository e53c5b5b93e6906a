// hystloop-reidentifier: refits the MEM hysteresis parameters from <rig>SENSOR on a schedule,
// off the receive thread, and publishes on <rig>PARAMS only candidates that pass every gate
// (fit succeeded and in range, residual bound, better on held-out branches than the set in
// use). See reident_service.hpp and reident_options.hpp; `--help` lists the options.
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "core/cli.hpp"
#include "core/config.hpp"
#include "core/logging.hpp"
#include "lcm/channels.hpp"
#include "lcm/connection.hpp"
#include "models/axis_coupling.hpp"
#include "models/model_descriptors.hpp"
#include "reidentifier/reident_options.hpp"
#include "reidentifier/reident_service.hpp"
#include "runtime/service_main.hpp"
#include "runtime/service_options.hpp"

int main(int argc, char** argv) try {
  using namespace hystloop;
  std::string model_list;  // "mem, pi, katalenic, linear": the registry's, for the description
  for (const std::string_view name : model_kind_names())
    model_list += (model_list.empty() ? "" : ", ") + std::string(name);
  CLI::App app{
      std::string(
          "hystloop-reidentifier: feeds <rig>SENSOR blocks (applied voltage and measured position per tick)\n"
          "to the online MEM estimator, refits every reidentifier.refit_period_s on a worker thread, and publishes\n"
          "on <rig>PARAMS only candidates that pass validation (signs, ranges, residual, a held-out branch\n"
          "better than the set in use), with their held-out residual. The initial set in use is the mem section\n"
          "(the compensator's keys, version 1); a newer valid set published by anyone else on <rig>PARAMS\n"
          "replaces it, and new versions are numbered above every one seen there or applied by the\n"
          "compensator on <rig>COMMAND. Status on <rig>STATUS\n"
          "(process \"reidentifier\" for axis x, \"reidentifier-y\" / \"reidentifier-z\" for the others) at 1 Hz.\n"
          "One process fits one axis (--axis, reidentifier.axis: x, y or z; a lab runs one per axis): the axis's "
          "ticks\n"
          "of every sensor block, the sets for it on <rig>PARAMS, and its sets carry it.\n"
          "Configuration keys: mem.*, reidentifier.{axis, rate_hz, refit_period_s,\n"
          "window_s, capacity_s, holdout_branches, min_relative_improvement, max_residual_rms_m,\n"
          "max_solver_time_s, reversal_dead_band_V, publish_invalid, stale_after_s, degraded_after_poisoned,\n"
          "lcm_queue, models, model_margin, model_period_s, model_decimation, pin_model}\n"
          "With reidentifier.models on, it also ranks fits of every online model (") +
      model_list +
      ") of its window on a held-out\n"
      "branch and publishes a model change on <rig>MODEL when another model wins by reidentifier.model_margin;\n"
      "hystloop-ctl pin-model pins the choice\n"
      "(see deploy/config/reidentifier.yaml). Exit codes: 0 clean stop, 1 runtime error, 2 bad configuration."};
  ServiceOptions service;
  bool publish_invalid = false;
  int axis = 0;
  add_service_options(app, service);
  app.add_flag(
      "--publish-invalid", publish_invalid,
      "Also publish refused candidates, with valid = false, for diagnosis (= --set reidentifier.publish_invalid=true)");
  CLI::Option* axis_option = add_axis_option(
      &app, "--axis", axis,
      "The stage axis this re-identifier fits (= --set reidentifier.axis=AXIS; default x): one process per axis");
  if (const auto exit_code = parse_command_line(app, argc, argv)) return *exit_code;
  if (publish_invalid) service.overrides.push_back("reidentifier.publish_invalid=true");
  if (axis_option->count() > 0) service.overrides.push_back("reidentifier.axis=" + std::string(axis_name(axis)));

  ReidentOptions options;
  RigLimitsOwn rig_limits;
  std::string url;
  const auto refused = configure_or_refuse("hystloop-reidentifier", [&] {
    url = set_up_service(ReidentService::kProcessName, service, {.adjust = {}, .read = [&](const Config& config) {
                                                                   options = read_reident_options(config);
                                                                   rig_limits = reident_rig_limits(config, options);
                                                                 }});
    if (options.axis != 0) {  // the log names the process as HX_STATUS does
      init_logging(ReidentService::process_name(options.axis), service.log_level,
                   service.log_file.empty() ? std::nullopt : std::optional<std::filesystem::path>(service.log_file));
    }
  });
  if (refused) return *refused;

  return run_service([&] {
    const ChannelNames names(service.rig_prefix);
    const OnlineMemOptions& e = options.estimator;
    spdlog::info("lcm: url {}, rig {}", url, names.prefix);
    spdlog::info("axis: {} (process \"{}\": fits {}'s ticks, takes and publishes sets for {})", axis_name(options.axis),
                 ReidentService::process_name(options.axis), axis_name(options.axis), axis_name(options.axis));
    spdlog::info("mem: {} (initial set in use, version 1)", MemDescriptor::summary_of(options.initial));
    spdlog::info(
        "reidentifier: rate_hz {}, refit_period_s {}, window_s {} ({} samples), capacity_s {} ({} samples), "
        "holdout_branches {}, min_relative_improvement {}, max_residual_rms_m {:.3g}, max_solver_time_s {}, "
        "publish_invalid {}, stale_after_s {}, degraded_after_poisoned {}, lcm_queue {}",
        options.rate_hz, options.refit_period_s, options.window_s, e.window_samples, options.capacity_s,
        e.capacity_samples, e.holdout_branches, e.min_relative_improvement, e.max_residual_rms_m,
        e.fit.max_solver_time_s, options.publish_invalid, options.stale_after_s, options.degraded_after_poisoned,
        options.lcm_queue);
    const ModelChoiceOptions& mc = options.models;
    spdlog::info("model choice: {}, candidates {}, margin {}, period {} s, decimation {}, pinned {}",
                 mc.enabled ? "on" : "off", mc.selector.selection.candidates.size(), mc.selector.margin, mc.period_s,
                 mc.selector.decimation, mc.pinned ? std::string(to_string(*mc.pinned)) : std::string("no"));
    auto lcm = open_lcm(url, service.allow_network);
    ReidentService reident(*lcm, names, options, {rig_limits});
    return reident.run();  // the service (and its refit worker) ends before run_service flushes the log
  });
} catch (...) {  // CLI11's set-up, before the handlers above exist: nothing escapes main
  return hystloop::exit_on_escaped_exception("hystloop-reidentifier");
}
