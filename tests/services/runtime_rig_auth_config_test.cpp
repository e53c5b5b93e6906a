// The `auth` section every service reads (runtime/rig_auth_config.hpp): absent or empty key_file
// is keyless, a key file loads with its skew, and a refused file or skew is a ConfigError naming
// the config's source, the field and the fix.
#include "runtime/rig_auth_config.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "auth/rig_key.hpp"

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

TEST(RigAuthConfig, UrlsThatLeaveTheHost) {
  EXPECT_FALSE(lcm_url_leaves_host("udpm://239.255.76.67:7667?ttl=0"));
  EXPECT_FALSE(lcm_url_leaves_host("udpm://239.255.76.67:7667"));
  EXPECT_FALSE(lcm_url_leaves_host("memq://"));
  EXPECT_TRUE(lcm_url_leaves_host("udpm://239.255.76.67:7667?ttl=1"));
  EXPECT_TRUE(lcm_url_leaves_host("udpm://239.255.76.67:7667?recv_buf_size=4194304&ttl=1"));
  EXPECT_TRUE(lcm_url_leaves_host("tcpq://hub:7700"));
}

}  // namespace
}  // namespace hystloop
