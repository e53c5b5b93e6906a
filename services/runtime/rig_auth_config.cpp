#include "runtime/rig_auth_config.hpp"

#include <ifaddrs.h>
#include <net/if.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "core/errors.hpp"
#include "core/process.hpp"
#include "lcm/url.hpp"
#include "runtime/config_validation.hpp"

namespace hystloop {

const std::vector<std::string>& rig_auth_config_keys() {
  static const std::vector<std::string> keys = {"auth.key_file", "auth.max_skew_s", "auth.keyless",
                                                "auth.allow_keyless_network"};
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

std::vector<std::string> shared_network_interfaces() {
  std::vector<std::string> names;
  ifaddrs* list = nullptr;
  if (::getifaddrs(&list) != 0) return {"(getifaddrs failed)"};  // unknown counts as shared
  for (const ifaddrs* a = list; a != nullptr; a = a->ifa_next) {
    if ((a->ifa_flags & IFF_UP) == 0 || (a->ifa_flags & IFF_LOOPBACK) != 0 || a->ifa_name == nullptr) continue;
    if (std::find(names.begin(), names.end(), a->ifa_name) == names.end()) names.emplace_back(a->ifa_name);
  }
  ::freeifaddrs(list);
  return names;
}

bool keyless_from_environment() {
  const char* v = std::getenv("HYSTLOOP_AUTH_KEYLESS");  // NOLINT(concurrency-mt-unsafe): read once at start
  return v != nullptr && std::string_view(v) == "1";
}

void check_keyless_choice(const Config& config, bool have_key, std::string_view url,
                          const std::vector<std::string>& shared_interfaces, bool keyless_from_env) {
  const bool keyless_in_config = config.get<bool>("auth.keyless", false);
  const bool keyless = keyless_in_config || (keyless_from_env && !have_key);
  const bool allow_network = config.get<bool>("auth.allow_keyless_network", false);
  validate_config_section(config, "", [&] {
    if (have_key && keyless_in_config) {
      throw ParameterError("auth.keyless", "true beside auth.key_file: choose one (a keyed rig, or a keyless one)");
    }
    if (have_key || !keyless) {
      if (!have_key) {
        throw ParameterError("auth.key_file",
                             "no rig key: a keyless service obeys anything on its network. Set auth.key_file to the "
                             "rig key (hystloop-ctl keygen --out FILE; deploy/hystloop makes run/rig.key), or "
                             "auth.keyless: true to run unauthenticated on purpose");
      }
      return;
    }
    if (allow_network || parse_lcm_url(url).provider == "memq") return;
    if (!shared_interfaces.empty() || lcm_url_leaves_host(url)) {
      throw ParameterError(
          "auth.keyless",
          fmt::format(
              "a keyless service on a network other hosts reach ({}{}): ttl=0 keeps packets from "
              "leaving, not from arriving, so any host there could arm the bridge. Run inside a private "
              "network namespace (deploy/hystloop and tools/netns-run do), set auth.key_file, or set "
              "auth.allow_keyless_network: true as well",
              shared_interfaces.empty() ? "" : fmt::format("interfaces {} up; ", fmt::join(shared_interfaces, ", ")),
              url));
    }
  });
}

namespace {
std::atomic<bool> g_watch_network{false};
std::atomic<bool> g_network_reached{false};
}  // namespace

void set_keyless_network_watch(bool on) noexcept {
  g_watch_network.store(on);
  g_network_reached.store(false);
}

std::string keyless_network_reached(std::vector<std::string> (*interfaces)()) {
  if (!g_watch_network.load() || g_network_reached.load()) return {};
  const std::vector<std::string> up = interfaces();
  if (up.empty()) return {};
  g_network_reached.store(true);
  std::string why = fmt::format(
      "a keyless service on a network other hosts reach: interfaces {} came up after the start, and any host "
      "there could now arm the bridge; stopping (set auth.key_file, or auth.allow_keyless_network: true)",
      fmt::join(up, ", "));
  spdlog::error("auth: {}", why);
  request_stop();
  return why;
}

void configure_rig_auth(const Config& config, std::string_view url) {
  std::shared_ptr<const RigAuth> auth = load_rig_auth(config);
  const bool env_keyless = keyless_from_environment();
  check_keyless_choice(config, auth != nullptr, url, shared_network_interfaces(), env_keyless);
  // Passed the check keyless and off the network: it must stay off it.
  set_keyless_network_watch(auth == nullptr && !config.get<bool>("auth.allow_keyless_network", false) &&
                            parse_lcm_url(url).provider != "memq");
  if (auth != nullptr) {
    spdlog::info(
        "auth: sensor blocks, commands, control, trajectories and parameters signed and checked with the rig "
        "key {} (max clock skew {} s)",
        config.get<std::string>("auth.key_file", ""), static_cast<double>(auth->max_skew_us) * 1e-6);
  } else {
    spdlog::warn(
        "auth: KEYLESS ({}{}): nothing this service receives is authenticated; any process on "
        "{} can arm the bridge and command the stage (docs/SECURITY.md)",
        config.get<bool>("auth.keyless", false) || !env_keyless ? "auth.keyless: true" : "HYSTLOOP_AUTH_KEYLESS=1",
        config.get<bool>("auth.allow_keyless_network", false) ? ", auth.allow_keyless_network: true" : "", url);
  }
  set_process_rig_auth(std::move(auth));
}

}  // namespace hystloop
