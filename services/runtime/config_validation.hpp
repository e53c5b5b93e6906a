#pragma once
// Parameter structs validate themselves and throw ParameterError naming their own field
// ("c3", "hysteresis.alpha"); a service reads them from a config section. This runs such a
// validate() and reports a failure as a ConfigError against the config's source, with the
// section prefix: "bridge.yaml: ro.c3: must be > 0 (got -1)".

#include <string>
#include <string_view>

#include "core/config.hpp"
#include "core/errors.hpp"

namespace hystloop {

template <class F>
void validate_config_section(const Config& config, std::string_view prefix, F&& validate) {
  try {
    validate();
  } catch (const ConfigError&) {
    throw;
  } catch (const ParameterError& e) {
    config.fail(std::string(prefix) + e.field(), e.reason());
  }
}

}  // namespace hystloop
