#include "runtime/service_options.hpp"

#include "core/cli.hpp"
#include "core/config.hpp"

namespace hystloop {

void add_service_options(CLI::App& app, ServiceOptions& options) {
  app.footer(
      "Exit status: 0 stopped as asked (SIGINT/SIGTERM, SHUTDOWN, --seconds); 1 a runtime failure; 2 a bad "
      "option, configuration or key file (the message names the field).");
  app.add_option("--config", options.config_files,
                 "YAML configuration file; repeat it to layer files, each later one's keys over the earlier ones' "
                 "(a map merged key by key, a value or a list replaced whole)")
      ->check(CLI::ExistingFile)
      ->allow_extra_args(false);
  app.add_option("--set", options.overrides, "Override a configuration value, KEY=VALUE (repeatable)");
  app.add_option("--lcm-url", options.lcm_url,
                 "LCM URL (default: $LCM_DEFAULT_URL, else udpm://239.255.76.67:7667?ttl=0)");
  app.add_flag("--allow-network", options.allow_network,
               "Accept an LCM URL whose packets can leave this host (ttl > 0, tcpq): for a multi-host lab");
  app.add_option("--rig", options.rig_prefix, "Channel prefix of the rig")->capture_default_str();
  app.add_option("--log-level", options.log_level, "trace, debug, info, warn or error")->capture_default_str();
  app.add_option("--log-file", options.log_file, "Also write the log to this file");
}

std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv) { return parse_cli(app, argc, argv); }

Config load_service_config(const ServiceOptions& options) {
  Config config;
  for (std::size_t i = 0; i < options.config_files.size(); ++i) {
    Config file = Config::load_file(options.config_files[i]);
    // An empty file is almost always the wrong file (or one being written): running on the defaults
    // without a word would hide that.
    if (file.keys().empty()) {
      throw ConfigError(options.config_files[i].string(), "",
                        "no keys in it (empty, or comments only): give the service's config (e.g. deploy/config/), or "
                        "leave --config out to run on the defaults");
    }
    if (i == 0) {
      config = std::move(file);
    } else {
      config.layer(file);
    }
  }
  config.apply_overrides(options.overrides);
  return config;
}

}  // namespace hystloop
