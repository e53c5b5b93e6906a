// The logger's channel table ("junk traffic blinds the logger"): the rig's six
// channels hold their slots from the start; 1000 junk names sent first take the spare slots
// and are then counted (bounded), never evicting the rig's channels.
#include "record/channel_table.hpp"

#include <gtest/gtest.h>

#include <string>

#include "support/allocation_counter.hpp"

namespace hystloop {
namespace {

TEST(ChannelTable, TheRigsChannelsHaveTheirSlotsFromTheStart) {
  const ChannelNames names("RIG1_");
  const ChannelTable table(names);
  ASSERT_EQ(table.size(), ChannelTable::kRigChannels);
  EXPECT_EQ(table[0].name_view(), "RIG1_SENSOR");
  EXPECT_EQ(table[0].kind, SequenceKind::kSensor);
  EXPECT_EQ(table[1].name_view(), "RIG1_COMMAND");
  EXPECT_EQ(table[1].kind, SequenceKind::kCommand);
  for (std::size_t i = 0; i < ChannelTable::kRigChannels; ++i) {
    EXPECT_TRUE(table[i].rig) << i;
    EXPECT_EQ(table[i].name_view(), names.prefix + std::string(kChannelSpecs[i].suffix));
  }
}

TEST(ChannelTable, AThousandJunkNamesFirstNeverEvictTheRigsChannels) {
  const ChannelNames names("HX_");
  ChannelTable table(names);
  std::size_t allocations = 0;
  std::size_t refused = 0;
  for (int round = 0; round < 3; ++round) {  // every junk name three times: counted once as a name
    for (int i = 0; i < 1000; ++i) {
      std::string junk = "HX_JUNK_";
      junk += std::to_string(i);
      if (i % 7 == 0) junk += "\x01\n";  // control bytes, as junk senders send
      const hystloop::testing::AllocationCounter counter;
      refused += !table.find_or_add(junk.c_str()).has_value();
      allocations += counter.allocations();
    }
  }
  EXPECT_EQ(allocations, 0u);
  const std::size_t spare = ChannelTable::kMaxChannels - ChannelTable::kRigChannels;
  EXPECT_EQ(table.size(), ChannelTable::kMaxChannels);
  EXPECT_EQ(refused, 3 * (1000 - spare));
  for (std::size_t i = 0; i < ChannelTable::kRigChannels; ++i) {
    const std::string rig = names.prefix + std::string(kChannelSpecs[i].suffix);
    const auto index = table.find_or_add(rig.c_str());
    ASSERT_TRUE(index.has_value()) << rig;
    EXPECT_EQ(*index, i) << rig;
  }
  const UnknownChannels& unknown = table.unknown();
  EXPECT_EQ(unknown.messages(), 3 * (1000 - spare));
  EXPECT_EQ(table.unrecorded_channels(), unknown.messages());
  EXPECT_EQ(unknown.distinct(), 1000 - spare);
  EXPECT_FALSE(unknown.distinct_is_lower_bound());
  ASSERT_EQ(unknown.kept_count(), UnknownChannels::kKeptNames);
  std::string first = "HX_JUNK_";
  first += std::to_string(spare);
  if (spare % 7 == 0) first += "\x01\n";  // as the loop above made it
  EXPECT_EQ(unknown.kept_name(0), first);
}

TEST(ChannelTable, TooLongNamesAreCountedNotRecorded) {
  ChannelTable table(ChannelNames("HX_"));
  const std::string long_name = "HX_" + std::string(100, 'A');
  EXPECT_FALSE(table.find_or_add(long_name.c_str()).has_value());
  EXPECT_EQ(table.unknown().messages(), 1u);
  EXPECT_EQ(table.unknown().kept_name(0), long_name.substr(0, UnknownChannels::kMaxName));
}

TEST(UnknownChannels, DistinctNamesAreCountedInBoundedMemoryThenAsALowerBound) {
  UnknownChannels unknown;
  for (std::size_t i = 0; i < 2 * UnknownChannels::kTrackedNames; ++i) {
    const std::string name = std::to_string(i);
    unknown.count(name.c_str(), name.size());
    unknown.count(name.c_str(), name.size());
  }
  EXPECT_EQ(unknown.messages(), 4 * UnknownChannels::kTrackedNames);
  EXPECT_EQ(unknown.distinct(), UnknownChannels::kTrackedNames);
  EXPECT_TRUE(unknown.distinct_is_lower_bound());
}

}  // namespace
}  // namespace hystloop
