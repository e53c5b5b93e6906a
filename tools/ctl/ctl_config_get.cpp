#include "ctl_config_get.hpp"

#include <cstdio>
#include <set>

#include "core/cli.hpp"
#include "core/config.hpp"

namespace hystloop::ctl {

namespace {

// The direct children of `key` among the tree's leaf keys: a map's keys, sorted (Config
// does not keep the file's order).
std::vector<std::string> children(const Config& cfg, const std::string& key) {
  const std::string prefix = key + ".";
  std::set<std::string> names;
  for (const auto& leaf : cfg.keys()) {
    if (leaf.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string rest = leaf.substr(prefix.size());
    names.insert(rest.substr(0, rest.find('.')));
  }
  return {names.begin(), names.end()};
}

}  // namespace

std::vector<std::string> config_get(const ConfigGetOptions& o) {
  if (o.key.empty()) throw ParameterError("key", "must not be empty (e.g. rig.lcm_url)");
  const Config cfg = Config::load_file(o.file);
  if (!cfg.has(o.key)) {
    if (o.default_value) return {*o.default_value};
    cfg.fail(o.key, "not in the file (give --default to accept its absence)");
  }
  std::vector<std::string> map_keys = children(cfg, o.key);
  if (!map_keys.empty()) return map_keys;
  try {
    return {cfg.get<std::string>(o.key)};
  } catch (const ConfigError&) {
    return cfg.get<std::vector<std::string>>(o.key);  // a list of scalars, or refused naming the key
  }
}

int run_config_get(const ConfigGetOptions& o) {
  try {
    for (const auto& line : config_get(o)) std::printf("%s\n", line.c_str());
    return 0;
  } catch (const ParameterError& e) {
    std::fprintf(stderr, "hystloop-ctl: config-get: %s\n", e.what());
    return kExitUsage;
  }
}

}  // namespace hystloop::ctl
