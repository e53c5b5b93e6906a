#pragma once
// hystloop-ctl config-get FILE KEY.PATH: one value of a YAML file, for shell scripts
// (deploy/hystloop reads deploy/rig.yaml with it instead of awk):
//   a scalar      -> its text, one line          rig.prefix          -> HX_
//   a list        -> one element per line        hosts.stage.services -> bridge \n logger
//   a map         -> its keys, one per line       hosts               -> control \n desk \n stage
// A missing key is refused (ParameterError naming the key and the file) unless a default is given.

#include <optional>
#include <string>
#include <vector>

namespace hystloop::ctl {

struct ConfigGetOptions {
  std::string file;
  std::string key;
  std::optional<std::string> default_value;
};

// The lines config-get prints. Throws ParameterError (ConfigError) for an unreadable or
// malformed file, a missing key without a default, or a list holding maps or lists.
std::vector<std::string> config_get(const ConfigGetOptions& o);

// Prints config_get's lines on stdout; 0 ok, 2 refused (message on stderr).
int run_config_get(const ConfigGetOptions& o);

}  // namespace hystloop::ctl
