#include "lcm/url.hpp"

#include <charconv>
#include <cstdlib>

#include "core/errors.hpp"

namespace hystloop {
namespace {

[[noreturn]] void refuse(std::string_view url, const std::string& why) {
  throw ParameterError("lcm.url", why + " (got \"" + std::string(url) + "\")");
}

bool parse_int(std::string_view text, int& value) {
  const char* end = text.data() + text.size();
  const auto result = std::from_chars(text.data(), end, value);
  return !text.empty() && result.ec == std::errc{} && result.ptr == end;
}

// "a.b.c.d" with every part 0..255 and a in 224..239.
bool is_ipv4_multicast_group(std::string_view address) {
  int parts = 0, first = 0;
  while (true) {
    const auto dot = address.find('.');
    int value = 0;
    if (!parse_int(address.substr(0, dot), value) || value < 0 || value > 255) return false;
    if (parts++ == 0) first = value;
    if (dot == std::string_view::npos) break;
    address.remove_prefix(dot + 1);
  }
  return parts == 4 && first >= 224 && first <= 239;
}

// "host[:port]": the port, when given, must be an integer 1..65535. LCM itself would fail
// only when it starts (atoi takes "77x" as 77, "99999" wraps), and the process exit 1 as if
// the network were down, without saying which part was wrong.
std::string_view checked_port(std::string_view url, std::string_view network) {
  const auto colon = network.rfind(':');
  if (colon == std::string_view::npos) return network;
  const std::string_view port = network.substr(colon + 1);
  int value = 0;
  if (!parse_int(port, value) || value < 1 || value > 65535) {
    refuse(url, "port must be an integer 1..65535, got '" + std::string(port) + "'");
  }
  return network.substr(0, colon);
}

}  // namespace

LcmUrl parse_lcm_url(std::string_view url) {
  const auto sep = url.find("://");
  if (sep == std::string_view::npos || sep == 0) refuse(url, "must look like provider://network?options");
  LcmUrl parsed;
  parsed.provider = std::string(url.substr(0, sep));
  std::string_view rest = url.substr(sep + 3);
  const auto question = rest.find('?');
  parsed.network = std::string(rest.substr(0, question));
  if (question != std::string_view::npos) parsed.options = std::string(rest.substr(question + 1));
  return parsed;
}

std::string lcm_url_option(const LcmUrl& url, std::string_view key) {
  std::string_view options = url.options;
  std::string found;
  while (!options.empty()) {
    const auto amp = options.find('&');
    const std::string_view pair = options.substr(0, amp);
    const auto eq = pair.find('=');
    if (pair.substr(0, eq) == key) found = std::string(eq == std::string_view::npos ? "" : pair.substr(eq + 1));
    if (amp == std::string_view::npos) break;
    options.remove_prefix(amp + 1);
  }
  return found;  // the last occurrence wins, as in LCM's own parser
}

std::string lcm_url_with_default_option(std::string_view url, std::string_view key, std::string_view value) {
  const LcmUrl parsed = parse_lcm_url(url);
  std::string_view options = parsed.options;
  while (!options.empty()) {  // present, even with an empty value: leave it to the caller
    const auto amp = options.find('&');
    const std::string_view pair = options.substr(0, amp);
    if (pair.substr(0, pair.find('=')) == key) return std::string(url);
    if (amp == std::string_view::npos) break;
    options.remove_prefix(amp + 1);
  }
  std::string out(url);
  out += parsed.options.empty() ? (url.find('?') == std::string_view::npos ? "?" : "") : "&";
  out += key;
  out += '=';
  out += value;
  return out;
}

std::string checked_lcm_url(std::string_view url, bool allow_network) {
  const LcmUrl parsed = parse_lcm_url(url);
  if (parsed.provider == "memq" || parsed.provider == "file") return std::string(url);
  if (parsed.provider == "tcpq") {
    checked_port(url, parsed.network);
    if (!allow_network) refuse(url, "tcpq reaches a hub over the network; pass the allow-network flag to use it");
    return std::string(url);
  }
  if (parsed.provider != "udpm") refuse(url, "provider must be udpm, memq, file or tcpq");

  if (!is_ipv4_multicast_group(checked_port(url, parsed.network)))
    refuse(url, "udpm needs an IPv4 multicast group 224.0.0.0/4");
  const std::string ttl_text = lcm_url_option(parsed, "ttl");
  int ttl = 0;
  if (!ttl_text.empty() && (!parse_int(ttl_text, ttl) || ttl < 0 || ttl > 255)) {
    refuse(url, "ttl must be an integer 0..255");
  }
  if (ttl > 0 && !allow_network) {
    refuse(url, "ttl > 0 sends packets off this host; pass the allow-network flag for a multi-host lab");
  }
  return std::string(url);
}

std::string resolve_lcm_url(std::string_view requested, bool allow_network) {
  if (!requested.empty()) return checked_lcm_url(requested, allow_network);
  if (const char* env = std::getenv("LCM_DEFAULT_URL"); env != nullptr && *env != '\0') {
    return checked_lcm_url(env, allow_network);
  }
  return checked_lcm_url(kDefaultLcmUrl, allow_network);
}

std::string resolve_lcm_url_for_10khz(std::string_view requested, bool allow_network) {
  std::string url = resolve_lcm_url(requested, allow_network);
  if (parse_lcm_url(url).provider == "udpm") {
    url = lcm_url_with_default_option(url, "recv_buf_size", kRecommendedRecvBufBytes);
  }
  return url;
}

}  // namespace hystloop
