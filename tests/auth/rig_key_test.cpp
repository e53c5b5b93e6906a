// The rig key file (auth/rig_key.hpp): keygen writes a 0600 file that loads back; a file open
// to group or others, of the wrong size, not hex, or missing is refused with a message naming
// the path and the fix.
#include "auth/rig_key.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "core/errors.hpp"
#include "support/refusal.hpp"
#include "support/tool_run.hpp"

namespace hystloop {
namespace {

namespace fs = std::filesystem;

class RigKeyTest : public ::testing::Test {
 protected:
  static std::string refusal(const fs::path& path) {
    const std::optional<ParameterError> e = testing::thrown<ParameterError>([&] { load_rig_key(path); });
    if (!e) {
      ADD_FAILURE() << "loaded " << path;
      return {};
    }
    EXPECT_EQ(e->field(), "auth.key_file");
    return e->what();
  }
  fs::path write(const std::string& name, const std::string& text, fs::perms perms) {
    fs::path p = dir_ / name;
    std::ofstream(p) << text;
    fs::permissions(p, perms);
    return p;
  }

  testing::ScratchDir scratch_{"hystloop_rig_key"};  // removed after the test
  fs::path dir_ = scratch_.dir();
};

TEST_F(RigKeyTest, KeygenWritesAnOwnerOnlyFileThatLoadsBack) {
  const fs::path p = dir_ / "rig.key";
  const RigKey key = generate_rig_key();
  write_rig_key(p, key, false);
  struct stat st {};
  ASSERT_EQ(::stat(p.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  EXPECT_EQ(fs::file_size(p), 65u);  // 64 hex digits and a newline
  EXPECT_EQ(load_rig_key(p).bytes, key.bytes);
  EXPECT_NE(generate_rig_key().bytes, key.bytes);
}

TEST_F(RigKeyTest, KeygenRefusesToOverwriteWithoutForceAndForceMakesItPrivate) {
  const fs::path p = write("rig.key", "old", fs::perms::owner_read | fs::perms::owner_write | fs::perms::others_read);
  try {
    write_rig_key(p, generate_rig_key(), false);
    FAIL() << "overwrote";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos) << e.what();
  }
  const RigKey key = generate_rig_key();
  write_rig_key(p, key, true);
  EXPECT_EQ(load_rig_key(p).bytes, key.bytes);
}

TEST_F(RigKeyTest, FileOpenToGroupOrOthersIsRefusedNamingPathAndChmod) {
  const RigKey key = generate_rig_key();
  const fs::path p = dir_ / "rig.key";
  write_rig_key(p, key, false);
  for (const fs::perms extra :
       {fs::perms::group_read, fs::perms::others_read, fs::perms::group_write, fs::perms::others_write}) {
    fs::permissions(p, fs::perms::owner_read | fs::perms::owner_write | extra);
    const std::string message = refusal(p);
    EXPECT_NE(message.find(p.string()), std::string::npos) << message;
    EXPECT_NE(message.find("chmod 600 " + p.string()), std::string::npos) << message;
  }
  fs::permissions(p, fs::perms::owner_read);
  EXPECT_EQ(load_rig_key(p).bytes, key.bytes);  // read-only for the owner is fine
}

TEST_F(RigKeyTest, WrongSizeOrNotHexIsRefused) {
  const auto owner = fs::perms::owner_read | fs::perms::owner_write;
  EXPECT_NE(refusal(write("short", std::string(63, 'a'), owner)).find("64 hex digits"), std::string::npos);
  EXPECT_NE(refusal(write("long", std::string(66, 'a'), owner)).find("64 hex digits"), std::string::npos);
  EXPECT_NE(refusal(write("empty", "", owner)).find("64 hex digits"), std::string::npos);
  EXPECT_NE(refusal(write("nothex", std::string(64, 'g'), owner)).find("not a hexadecimal key"), std::string::npos);
  EXPECT_NO_THROW(load_rig_key(write("ok", std::string(64, 'a') + "\n", owner)));
}

TEST_F(RigKeyTest, MissingFileOrDirectoryIsRefusedWithTheKeygenCommand) {
  const std::string message = refusal(dir_ / "absent.key");
  EXPECT_NE(message.find("absent.key"), std::string::npos);
  EXPECT_NE(message.find("hystloop-ctl keygen --out"), std::string::npos) << message;
  fs::permissions(dir_, fs::perms::owner_all);
  EXPECT_NE(refusal(dir_).find("not a regular file"), std::string::npos);
}

}  // namespace
}  // namespace hystloop
