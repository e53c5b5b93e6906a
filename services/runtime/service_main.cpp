#include "runtime/service_main.hpp"

#include <cstdio>
#include <exception>
#include <filesystem>

#include <spdlog/spdlog.h>

#include "core/cli.hpp"
#include "core/errors.hpp"
#include "core/logging.hpp"
#include "core/process.hpp"
#include "lcm/url.hpp"
#include "runtime/rig_auth_config.hpp"

namespace hystloop {

std::string set_up_service(std::string_view log_name, const ServiceOptions& options, const SetupSteps& steps) {
  init_logging(log_name, options.log_level,
               options.log_file.empty() ? std::nullopt : std::optional<std::filesystem::path>(options.log_file));
  Config config = load_service_config(options);
  if (steps.adjust) steps.adjust(config);
  if (steps.read) steps.read(config);
  std::string url = resolve_lcm_url_for_10khz(options.lcm_url, options.allow_network);
  if (steps.rig_auth) configure_rig_auth(config, url);
  return url;
}

std::optional<int> configure_or_refuse(const char* program, const std::function<void()>& configure) noexcept {
  try {
    configure();
    return std::nullopt;
  } catch (const std::exception& e) {  // ConfigError / ParameterError: a bad configuration
    std::fprintf(stderr, "%s: %s\n", program, e.what());
    return kExitUsage;
  } catch (...) {
    std::fprintf(stderr, "%s: unknown error while reading the configuration\n", program);
    return kExitUsage;
  }
}

int run_service(const std::function<int()>& body) noexcept {
  int rc = kExitFailure;
  try {
    install_stop_handlers();
    rc = body();
  } catch (const ParameterError& e) {
    spdlog::error("{}", e.what());
    rc = kExitUsage;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    rc = kExitFailure;
  } catch (...) {
    spdlog::error("unknown exception");
    rc = kExitFailure;
  }
  flush_logging();
  return rc;
}

}  // namespace hystloop
