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

// Socket receive buffer a 10 kHz subscriber should ask for (udpm option recv_buf_size;
// capped by net.core.rmem_max). With the kernel's default (~200 KB, ~200 small datagrams)
// a subscriber descheduled for 20 ms on a busy machine loses samples; measured with
// tests/integration/lcm_udpm_round_trip.sh: 0.4 % lost at 10 kHz without, none with.
inline constexpr std::string_view kRecommendedRecvBufBytes = "4194304";

// `url` with option key=value appended unless the URL already sets `key`, e.g.
// lcm_url_with_default_option(url, "recv_buf_size", kRecommendedRecvBufBytes) for udpm.
std::string lcm_url_with_default_option(std::string_view url, std::string_view key, std::string_view value);

// resolve_lcm_url for a process that receives a 10 kHz channel: a udpm URL gets the
// recommended receive buffer unless it sets one (the kernel's default loses samples when the
// process is descheduled for a moment).
std::string resolve_lcm_url_for_10khz(std::string_view requested, bool allow_network = false);

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
