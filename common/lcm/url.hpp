#pragma once
// Which LCM network a process joins. The default stays on this machine (ttl=0); a URL
// whose packets could leave the host is refused unless the caller says so explicitly
// (the deploy scripts of a real multi-host lab pass allow_network), so that a test or a
// demo never sprays 10 kHz multicast over somebody's lab network.

#include <string>
#include <string_view>

namespace hystloop {

inline constexpr std::string_view kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0";

// A URL split into its parts: "provider://network?key=value&key=value".
struct LcmUrl {
  std::string provider;  // "udpm", "memq", "file", "tcpq"
  std::string network;   // "239.255.76.67:7667", may be empty (memq)
  std::string options;   // "ttl=0&recv_buf_size=...", without '?'
};

// Splits a URL; throws ParameterError("lcm.url", ...) if it has no "provider://".
LcmUrl parse_lcm_url(std::string_view url);

// The value of option `key` in "k=v&k2=v2", or empty if absent.
std::string lcm_url_option(const LcmUrl& url, std::string_view key);

// Returns `url` if it is safe to use, else throws ParameterError("lcm.url", ...):
//  - udpm: a ttl above 0 (packets leave the host) needs allow_network; ttl must be an
//    integer 0..255 (absent = LCM's default, 0); the group must be an IPv4 multicast address.
//  - tcpq (a hub on some host) needs allow_network.
//  - memq (in-process) and file (event logs) are always local.
//  - any other provider is refused.
std::string checked_lcm_url(std::string_view url, bool allow_network = false);

// The URL a process uses: `requested` if non-empty, else $LCM_DEFAULT_URL if set, else
// kDefaultLcmUrl; checked as above.
std::string resolve_lcm_url(std::string_view requested, bool allow_network = false);

}  // namespace hystloop
