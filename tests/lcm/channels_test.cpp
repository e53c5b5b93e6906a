#include "lcm/channels.hpp"

#include <gtest/gtest.h>

#include <string>

#include "core/errors.hpp"
#include "hystloop/command_block_t.hpp"
#include "hystloop/model_params_t.hpp"
#include "hystloop/scan_t.hpp"
#include "hystloop/sensor_block_t.hpp"
#include "hystloop/sim_truth_t.hpp"

namespace hystloop {
namespace {

TEST(Channels, DefaultPrefixGivesTheDesignNames) {
  const ChannelNames names;
  EXPECT_EQ(names.prefix, "HX_");
  EXPECT_EQ(names.sensor, "HX_SENSOR");
  EXPECT_EQ(names.command, "HX_COMMAND");
  EXPECT_EQ(names.trajectory, "HX_TRAJECTORY");
  EXPECT_EQ(names.params, "HX_PARAMS");
  EXPECT_EQ(names.model, "HX_MODEL");
  EXPECT_EQ(names.status, "HX_STATUS");
  EXPECT_EQ(names.control, "HX_CONTROL");
  EXPECT_EQ(names.all_channels_regex(), "HX_.*");
}

TEST(Channels, AnotherRigGetsItsOwnNames) {
  const ChannelNames names("RIG2_");
  EXPECT_EQ(names.sensor, "RIG2_SENSOR");
  EXPECT_EQ(names.sim_truth, "RIG2_SIM_TRUTH");
  EXPECT_EQ(names.scan, "RIG2_SCAN");
  EXPECT_EQ(channel_name("RIG2_", kControlSuffix), "RIG2_CONTROL");
}

TEST(Channels, RefusesPrefixesThatAreNotLiteralRegexes) {
  for (const char* bad : {"", "hx_", "HX", "HX.*_", "H X_", "1HX_", "HX-A_", "ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456_"}) {
    try {
      ChannelNames names(bad);
      ADD_FAILURE() << "accepted \"" << bad << "\"";
    } catch (const ParameterError& e) {
      EXPECT_EQ(e.field(), "rig.prefix") << bad;
    }
  }
}

TEST(Channels, SpecsListEveryChannelOnce) {
  EXPECT_EQ(kChannelSpecs.size(), 9u);
  EXPECT_EQ(kChannelSpecs[8].type_name, std::string("hystloop.") + scan_t::getTypeName());
  EXPECT_EQ(kChannelSpecs[7].type_name, std::string("hystloop.") + sim_truth_t::getTypeName());
  EXPECT_EQ(kChannelSpecs[6].type_name, std::string("hystloop.") + model_params_t::getTypeName());
  EXPECT_EQ(kChannelSpecs[0].type_name, "hystloop.sensor_block_t");
  EXPECT_EQ(kChannelSpecs[1].type_name, "hystloop.command_block_t");
  EXPECT_EQ(kChannelSpecs[0].type_name, std::string("hystloop.") + sensor_block_t::getTypeName());
  EXPECT_EQ(kChannelSpecs[1].type_name, std::string("hystloop.") + command_block_t::getTypeName());
}

}  // namespace
}  // namespace hystloop
