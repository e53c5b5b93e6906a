// hystloop-compensator: answers every HX_SENSOR sample with the HX_COMMAND for a later tick,
// feedforward through the selected model's inverse, planned ahead of the bridge's clock.
#include <CLI/CLI.hpp>

#include <spdlog/spdlog.h>

#include "compensator/compensator_service.hpp"
#include "core/cli.hpp"
#include "core/process.hpp"
#include "lcm/connection.hpp"
#include "models/feedforward_mode.hpp"
#include "runtime/service_main.hpp"
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
  app.add_option("--mode", mode, "Feedforward: " + selectable_mode_choices() + " [compensator.mode]");
  app.add_option("--seconds", seconds, "Stop after this many seconds [compensator.run_seconds]");
  app.add_option("--summary-json", summary_json,
                 "At exit, write the run's figures (samples, command ticks and blocks, ticks planned too late, gaps, "
                 "parameter sets, block-to-answer latency) to this JSON file");
  if (const auto exit_code = parse_command_line(app, argc, argv)) return *exit_code;
  if (!mode.empty()) options.overrides.push_back("compensator.mode=" + mode);
  if (!seconds.empty()) options.overrides.push_back("compensator.run_seconds=" + seconds);

  CompensatorSettings settings;
  std::string url;
  const auto refused = configure_or_refuse("hystloop-compensator", [&] {
    url = set_up_service("compensator", options,
                         {.adjust =
                              [&](Config& config) {
                                for (const auto& file : params_files) merge_params_file(config, file);
                              },
                          .read = [&](const Config& config) { settings = load_compensator_settings(config); }});
  });
  if (refused) return *refused;

  return run_service([&] {
    if (settings.lock_memory) spdlog::info("memory: {}", lock_memory().detail);
    // Before LCM starts: its receive thread inherits this thread's scheduling.
    if (settings.rt_priority > 0) spdlog::info("scheduling: {}", set_realtime_priority(settings.rt_priority).detail);
    const ChannelNames channels(options.rig_prefix);
    auto lcm = open_lcm(url, options.allow_network);
    spdlog::info("lcm: {}", url);
    CompensatorService service(settings, *lcm, channels);
    if (!summary_json.empty()) service.write_summary_to(summary_json);
    return service.run();
  });
} catch (...) {  // CLI11's set-up, before the handlers above exist: nothing escapes main
  return hystloop::exit_on_escaped_exception("hystloop-compensator");
}
