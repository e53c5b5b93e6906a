#pragma once
// What the four services' main() share, so that each says only what is its own (flags, settings,
// what it logs at start): logging and the configuration first, where a refusal is "<program>:
// <why>" on stderr and exit 2 before anything runs; then the run, with the stop handlers installed,
// where a ParameterError is exit 2 and any other exception exit 1, logged, with the log flushed.

#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "core/config.hpp"
#include "runtime/service_options.hpp"

namespace hystloop {

struct SetupSteps {
  // Between loading the configuration and reading the settings: e.g. files merged over it, or a
  // flag that is an override of its key.
  std::function<void(Config&)> adjust;
  // Reads the service's settings from it (and throws for a bad one), before the URL and the rig's
  // authentication are looked at, so that a refusal names the most specific key first.
  std::function<void(const Config&)> read;
  bool rig_auth = true;  // configure the rig's authentication for the URL (off: no LCM is opened)
};

// Starts logging as `log_name`, loads the configuration (the file with --set overrides applied),
// runs `steps` on it and returns the LCM URL, resolved for a 10 kHz loop (lcm/url.hpp). Throws
// ConfigError / ParameterError for a bad configuration (call it inside configure_or_refuse).
std::string set_up_service(std::string_view log_name, const ServiceOptions& options, const SetupSteps& steps = {});

// Runs `configure`; an exception is printed as "<program>: <what>" on stderr and returned as
// kExitUsage. Empty when the configuration was accepted.
std::optional<int> configure_or_refuse(const char* program, const std::function<void()>& configure) noexcept;

// Installs the stop handlers and returns what `body` returns; kExitUsage for a ParameterError and
// kExitFailure for any other exception, each logged. The log is flushed on every path.
int run_service(const std::function<int()>& body) noexcept;

}  // namespace hystloop
