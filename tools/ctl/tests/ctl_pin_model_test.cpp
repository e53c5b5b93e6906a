// hystloop-ctl pin-model: each model name maps to the mode the re-identifier reads; "auto"/"off"
// unpin; anything else is refused naming the argument.
#include "ctl_pin_model.hpp"

#include <gtest/gtest.h>

#include "core/errors.hpp"
#include "hystloop/command_block_t.hpp"
#include "lcm/feedforward_mode.hpp"

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

TEST(CtlPinModel, EachAxisHasItsReidentifier) {
  EXPECT_EQ(reidentifier_process(0), "reidentifier");  // the name every one-axis rig knows
  EXPECT_EQ(reidentifier_process(1), "reidentifier-y");
  EXPECT_EQ(reidentifier_process(2), "reidentifier-z");
}

TEST(CtlPinModel, TheRefusalListsEveryModelAndAuto) {
  try {
    pin_model_mode("banning");
    FAIL() << "banning accepted";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("expected mem, pi, katalenic, linear or auto (got \"banning\")"),
              std::string::npos)
        << e.what();
  }
}

// The list the help and the refusal print comes from the model registry: every online model is in
// it and is accepted, and so is auto.
TEST(CtlPinModel, TheChoicesAreEveryOnlineModelAndAuto) {
  EXPECT_EQ(pin_model_choices(), "mem, pi, katalenic, linear or auto");
  for (const std::string_view name : model_kind_names()) {
    EXPECT_NE(pin_model_choices().find(name), std::string::npos) << name;
    const auto kind = parse_model_kind(name);
    ASSERT_TRUE(kind.has_value()) << name;
    EXPECT_EQ(to_string(*kind), name);
    EXPECT_EQ(pin_model_mode(std::string(name)), to_wire(mode_of(*kind))) << name;
  }
  EXPECT_EQ(model_kind_names().size(), static_cast<std::size_t>(kModelKindCount));
}

// The wire's mode numbers and FeedforwardMode are one numbering (lcm/feedforward_mode.hpp): every
// MODE_* round-trips, a number beyond them is refused, and the modes a config may name are listed.
TEST(FeedforwardModeWire, EveryModeRoundTripsAndOthersAreRefused) {
  for (std::int8_t w = command_block_t::MODE_OFF; w <= command_block_t::MODE_EXPERIMENT; ++w) {
    const auto mode = feedforward_mode_from_wire(w);
    ASSERT_TRUE(mode.has_value()) << int{w};
    EXPECT_EQ(to_wire(*mode), w);
  }
  EXPECT_EQ(feedforward_mode_from_wire(command_block_t::MODE_PI), FeedforwardMode::kPi);
  for (std::int8_t w : {std::int8_t{-1}, std::int8_t{100}, std::int8_t{127}}) {  // numbers no mode has
    EXPECT_FALSE(feedforward_mode_from_wire(w).has_value()) << int{w};
  }
  EXPECT_EQ(selectable_mode_choices(), "off, linear, mem, pi or katalenic");
}

}  // namespace
}  // namespace hystloop::ctl
