#pragma once
// The `auth` section every service reads (docs/SECURITY.md):
//   auth.key_file    path of the rig key (hystloop-ctl keygen; deploy/hystloop makes run/rig.key)
//   auth.max_skew_s  how far a signed message's counter may be from this host's clock [s]
//                    (0.05 .. 60, default 2): the hosts' clocks must agree to well within it
//   auth.keyless     true: run without a key, an explicit choice (default false: a service
//                    without auth.key_file refuses to start). The environment variable
//                    HYSTLOOP_AUTH_KEYLESS=1 makes the same choice for a process without a key
//                    (the test suite's, which runs in private namespaces); a key file wins over it.
//   auth.allow_keyless_network
//                    true: keyless even on a network other hosts reach (default false: keyless
//                    only inside a private network namespace, loopback the only interface up)
// A key is the default because nothing else keeps a rig to its operator: ttl=0 stops packets
// leaving a host, not arriving, so a keyless rig on a lab network obeys every host on it.

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/config.hpp"
#include "lcm/rig_auth.hpp"

namespace hystloop {

// "auth.key_file", "auth.max_skew_s", "auth.keyless", "auth.allow_keyless_network": for a
// service's list of known keys.
const std::vector<std::string>& rig_auth_config_keys();

// Reads and validates the section and loads the key. nullptr = keyless. Throws ConfigError
// naming the config's source and the field (a key file open to others, missing, wrong size).
std::shared_ptr<const RigAuth> load_rig_auth(const Config& config);

// True when packets sent on `url` can leave this host (udpm with ttl > 0, tcpq).
bool lcm_url_leaves_host(std::string_view url);

// The network interfaces of this network namespace that are up and not loopback: empty inside
// a private namespace (unshare -n, ip netns add), never empty on a host's own network.
std::vector<std::string> shared_network_interfaces();

// Whether a service without a key may run, given the config, the LCM URL and the interfaces
// that are up besides loopback (shared_network_interfaces()). Throws ConfigError naming the
// field and the fix when it may not: no key and no auth.keyless; a key and auth.keyless both;
// keyless on a network other hosts reach (an interface up, or a URL that leaves the host)
// without auth.allow_keyless_network. memq:// never leaves the process.
// keyless_from_environment: HYSTLOOP_AUTH_KEYLESS=1 was set.
void check_keyless_choice(const Config& config, bool have_key, std::string_view url,
                          const std::vector<std::string>& shared_interfaces, bool keyless_from_environment = false);

// True when HYSTLOOP_AUTH_KEYLESS is "1".
bool keyless_from_environment();

// load_rig_auth and check_keyless_choice, installed as the process's (set_process_rig_auth),
// with the start-up log line (a keyless rig warns at every start). Call after logging is set
// up, before any endpoint is made. A keyless service that may run only off the network has its
// network watched from then on (keyless_network_reached).
void configure_rig_auth(const Config& config, std::string_view url);

// A keyless service started inside a private namespace must not stay keyless once a network
// other hosts reach appears (a link brought up after the start check): its I/O loop calls this
// about once a second. The first time an interface besides loopback is up, it logs why, asks the
// process to stop (request_stop: the bridge's stop ramps to the safe state first) and returns the
// reason; later calls, and calls in a process that is keyed, allowed on the network or not
// watched, return an empty string. `interfaces` is for tests (default: shared_network_interfaces).
std::string keyless_network_reached(std::vector<std::string> (*interfaces)() = &shared_network_interfaces);
// Watch (or not) from now on: what configure_rig_auth decides, settable for tests.
void set_keyless_network_watch(bool on) noexcept;

}  // namespace hystloop
