#pragma once
// A model's section of a service config (mem.c1, pi.weights, katalenic.input_shaping.kind, ...)
// as assignments for the model's parameter table (param_table.hpp), so a config file, a
// hystloop-identify snippet merged into it and hystloop-model's --param all go through the same
// names and the same strict parsing. Start-up only.

#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/config.hpp"
#include "models/param_table.hpp"

namespace hystloop {

// Every key of `config` under "<model>.", in the config's (sorted) order. An assignment's name is
// the key below the section ("c1") and so is its origin: a refusal reads "c1: <reason>", which the
// caller prefixes with the section and the file. A list row is read as Config reads lists (its
// errors name the whole key); unknown names are left to apply() to refuse.
template <class S>
std::vector<Assignment> config_section(const Config& config, std::string_view model,
                                       std::span<const ParamSpec<S>> table) {
  const std::string prefix = std::string(model) + ".";
  std::vector<Assignment> out;
  for (const std::string& key : config.keys()) {
    if (key.rfind(prefix, 0) != 0) continue;
    std::string name = key.substr(prefix.size());
    const ParamSpec<S>* spec = find_spec(table, name);
    std::string value = spec != nullptr && spec->kind == ValueKind::list
                            ? format_list(config.get<std::vector<double>>(key))
                            : config.get<std::string>(key);
    out.push_back({name, std::move(value), name});
  }
  return out;
}

// D's (models/model_descriptors.hpp) section onto `settings` (the defaults), built and validated. Throws
// ParameterError naming the field below the section ("c1", an unknown one too): run it in
// validate_config_section(config, "<section>.", ...) for a ConfigError naming the key. The
// section is the model's name unless another part of the config holds the model's parameters
// (the bridge's ro: a MEM).
template <class D>
typename D::Params params_from_config(const Config& config, typename D::Settings settings,
                                      std::string_view section = D::name) {
  return params_from<D>(config_section(config, section, D::table()), std::move(settings));
}

// "<model>.<name>" for every row and alias of the table: the keys a config may hold.
template <class S>
void append_config_keys(std::vector<std::string>& keys, std::string_view model, std::span<const ParamSpec<S>> table) {
  for (const auto& row : table) {
    keys.push_back(std::string(model) + "." + std::string(row.name));
    if (!row.alias.empty()) keys.push_back(std::string(model) + "." + std::string(row.alias));
  }
}

}  // namespace hystloop
