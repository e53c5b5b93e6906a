#include "runtime/rig_auth_config.hpp"

#include <cmath>

#include <spdlog/spdlog.h>

#include "lcm/url.hpp"
#include "runtime/config_validation.hpp"

namespace hystloop {

const std::vector<std::string>& rig_auth_config_keys() {
  static const std::vector<std::string> keys = {"auth.key_file", "auth.max_skew_s"};
  return keys;
}

std::shared_ptr<const RigAuth> load_rig_auth(const Config& config) {
  const double skew_s = config.get_in_range("auth.max_skew_s", kDefaultMaxSkew_s, 0.05, 60.0);
  const std::string path = config.get<std::string>("auth.key_file", "");
  if (path.empty()) return nullptr;
  std::shared_ptr<const RigAuth> auth;
  validate_config_section(config, "",
                          [&] { auth = rig_auth_from_key_file(path, "auth.key_file", std::llround(skew_s * 1e6)); });
  return auth;
}

bool lcm_url_leaves_host(std::string_view url) {
  const LcmUrl parsed = parse_lcm_url(url);
  if (parsed.provider == "tcpq") return true;
  if (parsed.provider != "udpm") return false;
  const std::string ttl = lcm_url_option(parsed, "ttl");
  return !ttl.empty() && ttl != "0";
}

void configure_rig_auth(const Config& config, std::string_view url) {
  std::shared_ptr<const RigAuth> auth = load_rig_auth(config);
  if (auth != nullptr) {
    spdlog::info(
        "auth: commands, control, trajectories and parameters signed and checked with the rig key {} "
        "(max clock skew {} s)",
        config.get<std::string>("auth.key_file", ""), static_cast<double>(auth->max_skew_us) * 1e-6);
  } else if (lcm_url_leaves_host(url)) {
    spdlog::warn(
        "auth: no rig key (auth.key_file) on a network that leaves this host ({}): anything on it can "
        "arm the bridge and command the stage. Create a key with `hystloop-ctl keygen --out FILE` and set "
        "auth.key_file on every service (README \"Authenticated rig\")",
        url);
  }
  set_process_rig_auth(std::move(auth));
}

}  // namespace hystloop
