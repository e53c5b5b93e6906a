// The re-identifier's counters on HX_STATUS: one per refusal reason a refit can have, none that
// can never move ("refits_rejected_ok" would be one).
#include "reident/reident_counters.hpp"

#include <gtest/gtest.h>

#include <set>
#include <string>

namespace hystloop {
namespace {

TEST(ReidentCounters, EveryCounterHasOneNameAndNoneIsForAnOutcomeThatCannotHappen) {
  std::set<std::string> names;
  for (std::size_t i = 0; i < kReidentCounterCount; ++i) names.insert(std::string(counter_name(i)));
  EXPECT_EQ(names.size(), kReidentCounterCount);
  EXPECT_EQ(names.count("refits_rejected_ok"), 0u);
  EXPECT_EQ(names.count("refits_rejected_size_mismatch"), 1u);
  EXPECT_EQ(names.count("refits_rejected_poisoned_window"), 1u);
  EXPECT_EQ(counter_name(kReidentCounterCount), "unknown");
}

TEST(ReidentCounters, EachRefusalLandsOnItsOwnNameAndInTheTotal) {
  ReidentCounters c;
  c.add_rejected(FitStatus::no_improvement);
  c.add_rejected(FitStatus::no_improvement);
  c.add_rejected(FitStatus::size_mismatch);
  EXPECT_EQ(c.rejected(FitStatus::no_improvement), 2u);
  EXPECT_EQ(counter_name(ReidentCounters::rejected_index(FitStatus::no_improvement)), "refits_rejected_no_improvement");
  EXPECT_EQ(counter_name(ReidentCounters::rejected_index(FitStatus::size_mismatch)), "refits_rejected_size_mismatch");
  EXPECT_EQ(c.rejected_total(), 3u);
}

TEST(ReidentCounters, AnOutcomeThatIsNoRefusalIsCountedAsASolverFailure) {
  ReidentCounters c;
  c.add_rejected(FitStatus::ok);
  EXPECT_EQ(c.rejected(FitStatus::solver_failure), 1u);
  EXPECT_EQ(c.rejected_total(), 1u);
}

}  // namespace
}  // namespace hystloop
