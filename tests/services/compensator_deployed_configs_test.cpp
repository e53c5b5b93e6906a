// Every compensator config the repository ships loads, and the hardware example starts
// conservatively: its actuator the bridge's (deploy/config/bridge-comedi.yaml), learning off, no
// stage dynamics assumed.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "compensator/compensator_settings.hpp"
#include "core/config.hpp"

namespace hystloop {
namespace {

const std::filesystem::path kDeploy = std::filesystem::path(HYSTLOOP_SOURCE_DIR) / "deploy" / "config";

TEST(CompensatorDeployedConfigs, EveryShippedCompensatorConfigLoads) {
  int loaded = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(kDeploy)) {
    if (entry.path().filename() != "compensator.yaml") continue;
    EXPECT_NO_THROW(load_compensator_settings(Config::load_file(entry.path()))) << entry.path();
    ++loaded;
  }
  EXPECT_GE(loaded, 4);  // the product's, demo, two-mode, hardware
}

TEST(CompensatorDeployedConfigs, TheHardwareExampleStartsConservativelyWithTheBridgesActuator) {
  const CompensatorSettings s = load_compensator_settings(Config::load_file(kDeploy / "hardware" / "compensator.yaml"));
  const Config bridge = Config::load_file(kDeploy / "bridge-comedi.yaml");
  EXPECT_EQ(s.control.u_min_V, bridge.get<double>("actuator.u_min_V"));
  EXPECT_EQ(s.control.u_max_V, bridge.get<double>("actuator.u_max_V"));
  EXPECT_EQ(s.control.slew_V_per_s, bridge.get<double>("actuator.slew_V_per_s"));
  EXPECT_LE(s.control.u_max_V - s.control.u_min_V, 50.0);  // a small range, widened by the operator
  EXPECT_FALSE(s.control.learning.enabled);
  EXPECT_FALSE(s.control.stage.has_dynamics());
  EXPECT_EQ(s.control.models.linear.gain, bridge.get<double>("servo.nominal_gain_m_per_V"));
  EXPECT_EQ(bridge.get<double>("servo.kp"), 0.0);  // the servo off until its gains are set
  EXPECT_EQ(bridge.get<double>("servo.ki"), 0.0);
}

}  // namespace
}  // namespace hystloop
