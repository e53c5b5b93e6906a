// hystloop-reidentifier: refits the MEM hysteresis parameters from <rig>SENSOR on a schedule,
// off the receive thread, and publishes on <rig>PARAMS only candidates that pass every gate
// (fit succeeded and in range, residual bound, better on held-out branches than the set in
// use). See reident_service.hpp and reident_options.hpp; `--help` lists the options.
#include <cstdio>
#include <exception>
#include <memory>
#include <optional>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "core/config.hpp"
#include "core/errors.hpp"
#include "core/logging.hpp"
#include "core/process.hpp"
#include "lcm/channels.hpp"
#include "lcm/connection.hpp"
#include "lcm/url.hpp"
#include "reidentifier/reident_options.hpp"
#include "reidentifier/reident_service.hpp"
#include "runtime/rig_auth_config.hpp"
#include "runtime/service_options.hpp"

namespace {
constexpr int kExitBadConfiguration = 2;
}

int main(int argc, char** argv) {
  using namespace hystloop;
  CLI::App app{
      "hystloop-reidentifier: feeds <rig>SENSOR blocks (applied voltage and measured position per tick)\n"
      "to the online MEM estimator, refits every reidentifier.refit_period_s on a worker thread, and publishes\n"
      "on <rig>PARAMS only candidates that pass validation (signs, ranges, residual, a held-out branch\n"
      "better than the set in use), with their held-out residual. The initial set in use is mem.c1/c2/c3\n"
      "(the compensator's keys, version 1); a newer valid set published by anyone else on <rig>PARAMS\n"
      "replaces it, and new versions are numbered above every one seen there or applied by the\n"
      "compensator on <rig>COMMAND. Status on <rig>STATUS\n"
      "(process \"reidentifier\") at 1 Hz. Configuration keys: mem.{c1,c2,c3}, reidentifier.{rate_hz, refit_period_s,\n"
      "window_s, capacity_s, holdout_branches, min_relative_improvement, max_residual_rms_m,\n"
      "max_solver_time_s, reversal_dead_band_V, publish_invalid, stale_after_s, degraded_after_poisoned,\n"
      "lcm_queue, models, model_margin, model_period_s, model_decimation, pin_model}\n"
      "With reidentifier.models on, it also ranks MEM, PI, Katalenic and linear fits of its window on a held-out\n"
      "branch and publishes a model change on <rig>MODEL when another model wins by reidentifier.model_margin;\n"
      "hystloop-ctl pin-model pins the choice\n"
      "(see deploy/config/reidentifier.yaml). Exit codes: 0 clean stop, 1 runtime error, 2 bad configuration."};
  ServiceOptions service;
  bool publish_invalid = false;
  add_service_options(app, service);
  app.add_flag(
      "--publish-invalid", publish_invalid,
      "Also publish refused candidates, with valid = false, for diagnosis (= --set reidentifier.publish_invalid=true)");
  if (const auto exit_code = parse_command_line(app, argc, argv)) return *exit_code;

  ReidentOptions options;
  std::string url;
  std::unique_ptr<ChannelNames> names;
  try {
    init_logging(ReidentService::kProcessName, service.log_level,
                 service.log_file.empty() ? std::nullopt : std::optional(service.log_file));
    Config config = load_service_config(service);
    if (publish_invalid) config.apply_override("reidentifier.publish_invalid=true");
    options = read_reident_options(config);
    names = std::make_unique<ChannelNames>(service.rig_prefix);
    url = resolve_lcm_url_for_10khz(service.lcm_url, service.allow_network);
    configure_rig_auth(config, url);
  } catch (const ParameterError& e) {
    std::fprintf(stderr, "hystloop-reidentifier: %s\n", e.what());
    return kExitBadConfiguration;
  }

  try {
    install_stop_handlers();
    const OnlineMemOptions& e = options.estimator;
    spdlog::info("lcm: url {}, rig {}", url, names->prefix);
    spdlog::info("mem: c1 {:.9g} m/V, c2 {:.9g} m/V^(1+c3), c3 {:.9g} (initial set in use, version 1)",
                 options.initial.c1, options.initial.c2, options.initial.c3);
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
    int rc = 0;
    {
      ReidentService reident(*lcm, *names, options);
      rc = reident.run();
    }  // joins the refit worker before the log is flushed
    flush_logging();
    return rc;
  } catch (const ParameterError& e) {
    spdlog::error("{}", e.what());
    flush_logging();
    return kExitBadConfiguration;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    flush_logging();
    return 1;
  }
}
