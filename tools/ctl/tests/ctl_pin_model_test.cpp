// hystloop-ctl pin-model: each model name maps to the mode the re-identifier reads; "auto"/"off"
// unpin; anything else is refused naming the argument.
#include "ctl_pin_model.hpp"

#include <gtest/gtest.h>

#include "core/errors.hpp"
#include "hystloop/command_block_t.hpp"

namespace hystloop::ctl {
namespace {

TEST(CtlPinModel, NamesMapToTheModesTheReidentifierReads) {
  EXPECT_EQ(pin_model_mode("mem"), command_block_t::MODE_MEM);
  EXPECT_EQ(pin_model_mode("pi"), command_block_t::MODE_PI);
  EXPECT_EQ(pin_model_mode("katalenic"), command_block_t::MODE_KATALENIC);
  EXPECT_EQ(pin_model_mode("linear"), command_block_t::MODE_LINEAR);
  EXPECT_EQ(pin_model_mode("auto"), command_block_t::MODE_OFF);
  EXPECT_EQ(pin_model_mode("off"), command_block_t::MODE_OFF);
  for (const char* bad : {"", "banning", "MEM", "experiment"}) EXPECT_THROW(pin_model_mode(bad), ParameterError) << bad;
}

}  // namespace
}  // namespace hystloop::ctl
