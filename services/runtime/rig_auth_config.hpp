#pragma once
// The `auth` section every service reads (README "Authenticated rig"):
//   auth.key_file    path of the rig key (hystloop-ctl keygen); absent or empty = keyless
//   auth.max_skew_s  how far a signed message's counter may be from this host's clock [s]
//                    (0.05 .. 60, default 2): the hosts' clocks must agree to well within it
// A keyless service whose LCM URL leaves the host (ttl > 0, tcpq) warns once at start: anyone
// on that network can then move the stage.

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/config.hpp"
#include "lcm/rig_auth.hpp"

namespace hystloop {

// "auth.key_file", "auth.max_skew_s": for a service's list of known keys.
const std::vector<std::string>& rig_auth_config_keys();

// Reads and validates the section and loads the key. nullptr = keyless. Throws ConfigError
// naming the config's source and the field (a key file open to others, missing, wrong size).
std::shared_ptr<const RigAuth> load_rig_auth(const Config& config);

// True when packets sent on `url` can leave this host (udpm with ttl > 0, tcpq).
bool lcm_url_leaves_host(std::string_view url);

// load_rig_auth, installed as the process's (set_process_rig_auth), with the start-up log
// line (or the keyless-on-the-network warning). Call after logging is set up, before any
// endpoint is made.
void configure_rig_auth(const Config& config, std::string_view url);

}  // namespace hystloop
