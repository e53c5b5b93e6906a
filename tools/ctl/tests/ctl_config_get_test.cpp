// hystloop-ctl config-get: scalars, lists and maps of a YAML file as lines; missing keys,
// bad files and nested lists refused naming the key.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "core/errors.hpp"
#include "ctl_config_get.hpp"

using namespace hystloop;
using namespace hystloop::ctl;

namespace {

class ConfigGet : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = std::filesystem::temp_directory_path() / ("ctl_config_get_" + std::to_string(::getpid()) + ".yaml");
    std::ofstream(path_) << "rig:\n  prefix: HX_\n  ttl: 1\n  lcm_url: \"udpm://239.255.76.67:7667\"\n"
                            "hosts:\n  stage:\n    services: [bridge, logger]\n  desk:\n    services: []\n"
                            "  control:\n    services:\n      - compensator\n      - reidentifier\n"
                            "nested:\n  - {a: 1}\n";
  }
  void TearDown() override { std::filesystem::remove(path_); }
  std::vector<std::string> get(const std::string& key, std::optional<std::string> def = {}) {
    return config_get({path_.string(), key, std::move(def)});
  }
  std::filesystem::path path_;
};

using Lines = std::vector<std::string>;

TEST_F(ConfigGet, ScalarsAsTheirText) {
  EXPECT_EQ(get("rig.prefix"), Lines{"HX_"});
  EXPECT_EQ(get("rig.ttl"), Lines{"1"});
  EXPECT_EQ(get("rig.lcm_url"), Lines{"udpm://239.255.76.67:7667"});
}

TEST_F(ConfigGet, ListsOneElementPerLine) {
  EXPECT_EQ(get("hosts.stage.services"), (Lines{"bridge", "logger"}));
  EXPECT_EQ(get("hosts.control.services"), (Lines{"compensator", "reidentifier"}));
  EXPECT_EQ(get("hosts.desk.services"), Lines{});
}

TEST_F(ConfigGet, MapsTheirKeys) {
  EXPECT_EQ(get("hosts"), (Lines{"control", "desk", "stage"}));
  EXPECT_EQ(get("rig"), (Lines{"lcm_url", "prefix", "ttl"}));
}

TEST_F(ConfigGet, MissingKeyRefusedNamingItUnlessDefaulted) {
  try {
    get("hosts.lab.services");
    FAIL() << "a missing key was accepted";
  } catch (const ParameterError& e) {
    EXPECT_EQ(e.field(), "hosts.lab.services");
    EXPECT_NE(std::string(e.what()).find(path_.string()), std::string::npos) << e.what();
  }
  EXPECT_EQ(get("hosts.lab.services", "none"), Lines{"none"});
  EXPECT_THROW(get(""), ParameterError);
}

TEST_F(ConfigGet, ListOfMapsAndBadFilesRefused) {
  EXPECT_THROW(get("nested"), ParameterError);
  EXPECT_THROW(config_get({"/nonexistent/rig.yaml", "rig.prefix", {}}), ParameterError);
  std::ofstream(path_) << "rig: [unclosed\n";
  EXPECT_THROW(get("rig"), ParameterError);
}

TEST_F(ConfigGet, RunPrintsAndReturnsTheDocumentedCodes) {
  EXPECT_EQ(run_config_get({path_.string(), "rig.prefix", {}}), 0);
  EXPECT_EQ(run_config_get({path_.string(), "rig.missing", {}}), 2);
}

}  // namespace
