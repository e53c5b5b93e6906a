#include "lcm/url.hpp"

#include <gtest/gtest.h>

#include <cstdlib>

#include "core/errors.hpp"

namespace hystloop {
namespace {

void expect_refused(std::string_view url, bool allow_network = false) {
  try {
    checked_lcm_url(url, allow_network);
    ADD_FAILURE() << "accepted " << url;
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "lcm.url");
  }
}

TEST(LcmUrl, DefaultStaysOnThisHost) {
  EXPECT_EQ(kDefaultLcmUrl, "udpm://239.255.76.67:7667?ttl=0");
  EXPECT_EQ(checked_lcm_url(kDefaultLcmUrl), kDefaultLcmUrl);
  EXPECT_EQ(lcm_url_option(parse_lcm_url(kDefaultLcmUrl), "ttl"), "0");
}

TEST(LcmUrl, ParsesProviderNetworkAndOptions) {
  const auto url = parse_lcm_url("udpm://239.1.2.3:7000?recv_buf_size=2097152&ttl=1");
  EXPECT_EQ(url.provider, "udpm");
  EXPECT_EQ(url.network, "239.1.2.3:7000");
  EXPECT_EQ(lcm_url_option(url, "recv_buf_size"), "2097152");
  EXPECT_EQ(lcm_url_option(url, "ttl"), "1");
  EXPECT_EQ(lcm_url_option(url, "missing"), "");
}

TEST(LcmUrl, TtlAboveZeroNeedsTheAllowFlag) {
  expect_refused("udpm://239.255.76.67:7667?ttl=1");
  expect_refused("udpm://239.255.76.67:7667?ttl=0&ttl=1");  // LCM takes the last one
  EXPECT_NO_THROW(checked_lcm_url("udpm://239.255.76.67:7667?ttl=1", true));
  EXPECT_NO_THROW(checked_lcm_url("udpm://239.255.76.67:7667"));  // LCM's default ttl is 0
}

TEST(LcmUrl, RefusesMalformedUrls) {
  for (const char* bad :
       {"", "239.255.76.67:7667", "://x", "udpm://239.255.76.67:7667?ttl=abc", "udpm://239.255.76.67:7667?ttl=-1",
        "udpm://239.255.76.67:7667?ttl=256", "udpm://10.0.0.1:7667?ttl=0", "carrier-pigeon://x"}) {
    expect_refused(bad, true);
  }
}

// A bad port reached LCM, which failed at start-up (exit 1, "LCM could not start") without
// naming it; refused here, naming the port, so that a service exits 2 with the reason.
TEST(LcmUrl, BadPortIsRefusedNamingIt) {
  for (const char* bad :
       {"udpm://239.255.76.67:99999?ttl=0", "udpm://239.255.76.67:0?ttl=0", "udpm://239.255.76.67:77x?ttl=0",
        "udpm://239.255.76.67:?ttl=0", "udpm://239.255.76.67:-1", "tcpq://lab-hub:70000"}) {
    try {
      checked_lcm_url(bad, true);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const ParameterError& e) {
      EXPECT_EQ(e.field(), "lcm.url");
      EXPECT_NE(std::string(e.what()).find("port must be an integer 1..65535"), std::string::npos) << e.what();
    }
  }
  EXPECT_NO_THROW(checked_lcm_url("udpm://239.255.76.67:1?ttl=0"));
  EXPECT_NO_THROW(checked_lcm_url("udpm://239.255.76.67:65535?ttl=0"));
  EXPECT_NO_THROW(checked_lcm_url("udpm://239.255.76.67?ttl=0"));  // LCM's default port
  EXPECT_NO_THROW(checked_lcm_url("tcpq://lab-hub:7700", true));
  // The group's every part is an octet.
  expect_refused("udpm://239.255.76.300:7667?ttl=0");
  expect_refused("udpm://239.255.76:7667?ttl=0");
  expect_refused("udpm://239.255.76.67.1:7667?ttl=0");
}

TEST(LcmUrl, LocalProvidersAreAlwaysFine_TcpqNeedsTheFlag) {
  EXPECT_NO_THROW(checked_lcm_url("memq://"));
  EXPECT_NO_THROW(checked_lcm_url("file:///tmp/x.lcmlog?mode=r"));
  expect_refused("tcpq://lab-hub:7700");
  EXPECT_NO_THROW(checked_lcm_url("tcpq://lab-hub:7700", true));
}

TEST(LcmUrl, AddsAnOptionOnlyWhenAbsent) {
  EXPECT_EQ(lcm_url_with_default_option(kDefaultLcmUrl, "recv_buf_size", kRecommendedRecvBufBytes),
            "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304");
  EXPECT_EQ(lcm_url_with_default_option("udpm://239.1.1.1:7667", "ttl", "0"), "udpm://239.1.1.1:7667?ttl=0");
  EXPECT_EQ(lcm_url_with_default_option("udpm://239.1.1.1:7667?", "ttl", "0"), "udpm://239.1.1.1:7667?ttl=0");
  EXPECT_EQ(lcm_url_with_default_option("udpm://239.1.1.1:7667?recv_buf_size=1", "recv_buf_size", "9"),
            "udpm://239.1.1.1:7667?recv_buf_size=1");
  const auto url = lcm_url_with_default_option(kDefaultLcmUrl, "recv_buf_size", "65536");
  EXPECT_EQ(checked_lcm_url(url), url);
}

TEST(LcmUrl, ResolvesRequestedThenEnvironmentThenDefault) {
  ::unsetenv("LCM_DEFAULT_URL");
  EXPECT_EQ(resolve_lcm_url(""), kDefaultLcmUrl);
  ::setenv("LCM_DEFAULT_URL", "memq://", 1);
  EXPECT_EQ(resolve_lcm_url(""), "memq://");
  EXPECT_EQ(resolve_lcm_url("udpm://239.1.1.1:7001?ttl=0"), "udpm://239.1.1.1:7001?ttl=0");
  ::setenv("LCM_DEFAULT_URL", "udpm://239.255.76.67:7667?ttl=3", 1);
  EXPECT_THROW(resolve_lcm_url(""), ParameterError);  // the environment is checked too
  ::unsetenv("LCM_DEFAULT_URL");
}

}  // namespace
}  // namespace hystloop
