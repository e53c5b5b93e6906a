// hystloop-compensator: answers every HX_SENSOR sample with the HX_COMMAND for a later tick,
// feedforward through the selected model's inverse, planned ahead of the bridge's clock.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

#include <spdlog/spdlog.h>

#include "compensator/compensator_service.hpp"
#include "core/cli.hpp"
#include "core/logging.hpp"
#include "core/process.hpp"
#include "lcm/connection.hpp"
#include "lcm/url.hpp"
#include "runtime/rig_auth_config.hpp"
#include "runtime/service_options.hpp"

int main(int argc, char** argv) try {
  using namespace hystloop;
  CLI::App app{
      "hystloop-compensator: turns the reference (HX_TRAJECTORY) into the feedforward voltage that makes "
      "the stage follow it, through the inverse of the selected hysteresis model, one step per tick; answers "
      "each HX_SENSOR block with the commands (HX_COMMAND) for compensator.horizon_s ahead of the bridge's "
      "clock; swaps in new MEM parameters (HX_PARAMS) at reversals; mode and experiments change through "
      "HX_CONTROL (the servo's gains are the bridge's)."};
  ServiceOptions options;
  add_service_options(app, options);
  std::vector<std::filesystem::path> params_files;
  std::string mode, seconds, summary_json;
  app.add_option("--params", params_files,
                 "Model parameters as `hystloop-identify --out` writes them (merged over the config; repeatable)")
      ->check(CLI::ExistingFile);
  app.add_option("--mode", mode, "Feedforward: mem, pi, katalenic, linear or off [compensator.mode]");
  app.add_option("--seconds", seconds, "Stop after this many seconds [compensator.run_seconds]");
  app.add_option("--summary-json", summary_json,
                 "At exit, write the run's figures (samples, command ticks and blocks, ticks planned too late, gaps, "
                 "parameter sets, block-to-answer latency) to this JSON file");
  if (const auto exit_code = parse_command_line(app, argc, argv)) return *exit_code;
  if (!mode.empty()) options.overrides.push_back("compensator.mode=" + mode);
  if (!seconds.empty()) options.overrides.push_back("compensator.run_seconds=" + seconds);

  CompensatorSettings settings;
  std::string url;
  try {
    init_logging("compensator", options.log_level,
                 options.log_file.empty() ? std::nullopt : std::optional<std::filesystem::path>(options.log_file));
    Config config = load_service_config(options);
    for (const auto& file : params_files) merge_params_file(config, file);
    settings = load_compensator_settings(config);
    url = resolve_lcm_url_for_10khz(options.lcm_url, options.allow_network);
    configure_rig_auth(config, url);
  } catch (const std::exception& e) {  // ConfigError / ParameterError: bad configuration
    std::fprintf(stderr, "hystloop-compensator: %s\n", e.what());
    return kExitUsage;
  }

  try {
    install_stop_handlers();
    if (settings.lock_memory) spdlog::info("memory: {}", lock_memory().detail);
    // Before LCM starts: its receive thread inherits this thread's scheduling.
    if (settings.rt_priority > 0) spdlog::info("scheduling: {}", set_realtime_priority(settings.rt_priority).detail);
    const ChannelNames channels(options.rig_prefix);
    auto lcm = open_lcm(url, options.allow_network);
    spdlog::info("lcm: {}", url);
    CompensatorService service(settings, *lcm, channels);
    if (!summary_json.empty()) service.write_summary_to(summary_json);
    const int rc = service.run();
    flush_logging();
    return rc;
  } catch (const ParameterError& e) {
    std::fprintf(stderr, "hystloop-compensator: %s\n", e.what());
    return kExitUsage;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    flush_logging();
    return 1;
  }
} catch (...) {  // CLI11's set-up, before the handlers above exist: nothing escapes main
  return hystloop::exit_on_escaped_exception("hystloop-compensator");
}
