#pragma once
// Options every service takes, with one spelling everywhere:
//   --config FILE       YAML configuration (see deploy/config/*.yaml)
//   --set KEY=VALUE     override one configuration value (repeatable)
//   --lcm-url URL       LCM network (default: $LCM_DEFAULT_URL or udpm://239.255.76.67:7667?ttl=0)
//   --allow-network     accept an LCM URL whose packets can leave this host (ttl > 0, tcpq)
//   --rig PREFIX        channel prefix of the rig (default HX_)
//   --log-level LEVEL   trace|debug|info|warn|error (default info)
//   --log-file FILE     also log to this file

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "core/config.hpp"

namespace hystloop {

struct ServiceOptions {
  // The service's config, then files layered over it in order (Config::layer): a scenario's or a
  // rig's settings without a copy of the whole file.
  std::vector<std::filesystem::path> config_files;
  std::vector<std::string> overrides;
  std::string lcm_url;
  bool allow_network = false;
  std::string rig_prefix = "HX_";
  std::string log_level = "info";
  std::filesystem::path log_file;
};

void add_service_options(CLI::App& app, ServiceOptions& options);

// Parses the command line. Returns the exit code when the program must stop now (0 after
// --help, 2 with the reason on stderr for a bad option); nothing when it goes on.
std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv);

// The configuration file (or an empty tree) with --set overrides applied.
// Throws ConfigError naming the file and the field.
Config load_service_config(const ServiceOptions& options);

}  // namespace hystloop
