// The `auth` section every service reads (runtime/rig_auth_config.hpp): absent or empty key_file
// is keyless, a key file loads with its skew, and a refused file or skew is a ConfigError naming
// the config's source, the field and the fix.
#include "runtime/rig_auth_config.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "auth/rig_key.hpp"
#include "core/process.hpp"

namespace hystloop {
namespace {

namespace fs = std::filesystem;

class RigAuthConfigTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hystloop_rig_auth_config_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    key_path_ = dir_ / "rig.key";
    key_ = generate_rig_key();
    write_rig_key(key_path_, key_, false);
  }
  void TearDown() override { fs::remove_all(dir_); }
  Config config(const std::string& yaml) { return Config::from_string(yaml, "bridge.yaml"); }

  fs::path dir_, key_path_;
  RigKey key_;
};

TEST_F(RigAuthConfigTest, AbsentOrEmptyKeyFileIsKeyless) {
  EXPECT_EQ(load_rig_auth(config("{}")), nullptr);
  Config c = config("auth: {max_skew_s: 1}");
  c.apply_override("auth.key_file=\"\"");  // what tools/replay-check passes
  EXPECT_EQ(load_rig_auth(c), nullptr);
}

TEST_F(RigAuthConfigTest, KeyFileLoadsWithItsSkew) {
  const auto auth = load_rig_auth(config("auth: {key_file: " + key_path_.string() + ", max_skew_s: 0.5}"));
  ASSERT_NE(auth, nullptr);
  EXPECT_EQ(auth->key.bytes, key_.bytes);
  EXPECT_EQ(auth->max_skew_us, 500000);
  EXPECT_EQ(load_rig_auth(config("auth: {key_file: " + key_path_.string() + "}"))->max_skew_us, 2000000);
}

TEST_F(RigAuthConfigTest, OpenKeyFileIsRefusedNamingSourceFieldAndFix) {
  fs::permissions(key_path_, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  try {
    load_rig_auth(config("auth: {key_file: " + key_path_.string() + "}"));
    FAIL() << "loaded a key readable by the group";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("bridge.yaml: auth.key_file: " + key_path_.string(), 0), 0u) << what;
    EXPECT_NE(what.find("chmod 600 " + key_path_.string()), std::string::npos) << what;
  }
}

TEST_F(RigAuthConfigTest, SkewOutOfRangeIsRefused) {
  for (const char* skew : {"0", "-1", "0.01", "61"}) {
    EXPECT_THROW(load_rig_auth(config(std::string("auth: {max_skew_s: ") + skew + "}")), ConfigError) << skew;
  }
}

// A service without a key runs only by an explicit choice, and on a network other hosts reach
// only by a second one: ttl=0 does not stop packets arriving from the LAN.
TEST(RigAuthKeyless, NoKeyWithoutTheChoiceIsRefusedNamingTheFix) {
  const Config c = Config::from_string("{}", "bridge.yaml");
  try {
    check_keyless_choice(c, false, "udpm://239.255.76.67:7667?ttl=0", {});
    FAIL() << "a service without a key started without auth.keyless";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("bridge.yaml: auth.key_file: no rig key", 0), 0u) << what;
    EXPECT_NE(what.find("hystloop-ctl keygen"), std::string::npos) << what;
    EXPECT_NE(what.find("auth.keyless: true"), std::string::npos) << what;
  }
  EXPECT_NO_THROW(check_keyless_choice(c, true, "udpm://239.255.76.67:7667?ttl=0", {"eth0"}));  // keyed: anywhere
}

TEST(RigAuthKeyless, KeylessRunsInAPrivateNamespaceOnly) {
  const Config keyless = Config::from_string("auth: {keyless: true}", "c.yaml");
  EXPECT_NO_THROW(check_keyless_choice(keyless, false, "udpm://239.255.76.67:7667?ttl=0", {}));
  EXPECT_NO_THROW(check_keyless_choice(keyless, false, "memq://", {"eth0"}));
  try {
    check_keyless_choice(keyless, false, "udpm://239.255.76.67:7667?ttl=0", {"eth0", "veth1"});
    FAIL() << "keyless on a host network";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("c.yaml: auth.keyless: a keyless service on a network other hosts reach", 0), 0u) << what;
    EXPECT_NE(what.find("eth0, veth1"), std::string::npos) << what;
    EXPECT_NE(what.find("auth.allow_keyless_network"), std::string::npos) << what;
  }
  // A URL that leaves the host is shared whatever the interfaces say.
  EXPECT_THROW(check_keyless_choice(keyless, false, "tcpq://hub:7700", {}), ConfigError);
  const Config allowed = Config::from_string("auth: {keyless: true, allow_keyless_network: true}", "c.yaml");
  EXPECT_NO_THROW(check_keyless_choice(allowed, false, "udpm://239.255.76.67:7667?ttl=1", {"eth0"}));
  // Allowing the network is not the keyless choice itself.
  EXPECT_THROW(check_keyless_choice(Config::from_string("auth: {allow_keyless_network: true}", "c.yaml"), false,
                                    "udpm://239.255.76.67:7667?ttl=0", {}),
               ConfigError);
}

TEST(RigAuthKeyless, TheEnvironmentsChoiceCountsOnlyWithoutAKeyAndNotOnAHostNetwork) {
  const Config none = Config::from_string("{}", "c.yaml");
  EXPECT_NO_THROW(check_keyless_choice(none, false, "udpm://239.255.76.67:7667?ttl=0", {}, true));
  EXPECT_NO_THROW(check_keyless_choice(none, true, "udpm://239.255.76.67:7667?ttl=0", {"eth0"}, true));  // keyed
  EXPECT_THROW(check_keyless_choice(none, false, "udpm://239.255.76.67:7667?ttl=0", {"eth0"}, true), ConfigError);
}

TEST(RigAuthKeyless, KeyAndKeylessTogetherIsRefused) {
  EXPECT_THROW(check_keyless_choice(Config::from_string("auth: {keyless: true}", "c.yaml"), true,
                                    "udpm://239.255.76.67:7667?ttl=0", {}),
               ConfigError);
}

TEST(RigAuthConfig, UrlsThatLeaveTheHost) {
  EXPECT_FALSE(lcm_url_leaves_host("udpm://239.255.76.67:7667?ttl=0"));
  EXPECT_FALSE(lcm_url_leaves_host("udpm://239.255.76.67:7667"));
  EXPECT_FALSE(lcm_url_leaves_host("memq://"));
  EXPECT_TRUE(lcm_url_leaves_host("udpm://239.255.76.67:7667?ttl=1"));
  EXPECT_TRUE(lcm_url_leaves_host("udpm://239.255.76.67:7667?recv_buf_size=4194304&ttl=1"));
  EXPECT_TRUE(lcm_url_leaves_host("tcpq://hub:7700"));
}

std::vector<std::string> no_interfaces() { return {}; }
std::vector<std::string> veth_up() { return {"veth0"}; }

// A keyless service watched after its start: nothing while only loopback is up; the first
// interface up stops the process, once, naming it; a keyed or allowed service is not watched.
TEST(RigAuthKeyless, AnInterfaceComingUpStopsAWatchedKeylessService) {
  install_stop_handlers();
  set_keyless_network_watch(false);
  EXPECT_EQ(keyless_network_reached(&veth_up), "");
  EXPECT_FALSE(stop_requested());
  set_keyless_network_watch(true);
  EXPECT_EQ(keyless_network_reached(&no_interfaces), "");
  EXPECT_FALSE(stop_requested());
  const std::string why = keyless_network_reached(&veth_up);
  EXPECT_NE(why.find("veth0"), std::string::npos) << why;
  EXPECT_TRUE(stop_requested());
  EXPECT_EQ(keyless_network_reached(&veth_up), "");  // said once
  set_keyless_network_watch(false);
}

}  // namespace
}  // namespace hystloop
