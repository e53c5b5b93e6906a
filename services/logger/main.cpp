// hystloop-logger: records the rig's channels to rotating LCM event logs (lcm-logplayer
// and lcm-spy read them), counts every message, drop and tick gap, reports them in
// HX_STATUS at 1 Hz and in a summary JSON written at close. See logger_service.hpp and
// logger_options.hpp; `hystloop-logger --help` lists the options.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "core/cli.hpp"
#include "core/config.hpp"
#include "lcm/channels.hpp"
#include "lcm/connection.hpp"
#include "logger/logger_options.hpp"
#include "logger/logger_service.hpp"
#include "runtime/service_main.hpp"
#include "runtime/service_options.hpp"

int main(int argc, char** argv) try {
  using namespace hystloop;
  CLI::App app{
      "hystloop-logger: records the rig's LCM channels to rotating event logs\n"
      "(<out-dir>/<file-prefix>hystloop-YYYYmmdd-HHMMSS.NNN.lcmlog, read by lcm-logplayer and lcm-spy),\n"
      "detects missing ticks between the blocks on <rig>SENSOR and <rig>COMMAND, reports in <rig>STATUS\n"
      "(process \"logger\")"
      " and writes <recording>.summary.json at close (SIGINT, SIGTERM or control SHUTDOWN).\n"
      "Each logger flag equals --set logger.<key>=VALUE (keys: out_dir, file_prefix, max_file_mb, max_file_s,\n"
      "summary, channels, queue_mb, lcm_queue, flush_interval_s, restart_threshold, command_resume_s).\n"
      "Exit status: 0; 1 if a disk fault lost events (see the summary's \"disk\") or the summary could not be\n"
      "written; 2 for a bad option or configuration."};
  ServiceOptions service;
  LoggerFlags flags;
  add_service_options(app, service);
  app.footer("");  // its own exit status is in the description above (a disk fault is 1)
  add_logger_options(app, flags);
  if (const auto exit_code = parse_command_line(app, argc, argv)) return *exit_code;

  LoggerOptions options;
  std::string url;
  const auto refused = configure_or_refuse("hystloop-logger", [&] {
    url = set_up_service(LoggerService::kProcessName, service,
                         {.adjust = [&](Config& config) { apply_logger_flags(flags, config); },
                          .read = [&](const Config& config) { options = read_logger_options(config); }});
  });
  if (refused) return *refused;

  return run_service([&] {
    const ChannelNames names(service.rig_prefix);
    spdlog::info("lcm: url {}, rig {}", url, names.prefix);
    spdlog::info("logger: out_dir {}, file_prefix '{}', max_file_mb {}, max_file_s {}, summary {}, channels '{}'",
                 options.out_dir.string(), options.file_prefix, options.max_file_mb, options.max_file_s,
                 options.summary_file.empty() ? "<next to the logs>" : options.summary_file.string(),
                 options.channels.empty() ? names.all_channels_regex() : options.channels);
    spdlog::info("logger: queue_mb {}, lcm_queue {}, flush_interval_s {}, restart_threshold {}", options.queue_mb,
                 options.lcm_queue, options.flush_interval_s, options.restart_threshold);
    auto lcm = open_lcm(url, service.allow_network);
    LoggerService logger(*lcm, names, options);
    return logger.run();
  });
} catch (...) {  // CLI11's set-up, before the handlers above exist: nothing escapes main
  return hystloop::exit_on_escaped_exception("hystloop-logger");
}
