#include "simulator/sim_outputs.h"

#include <string>

#include <gtest/gtest.h>

namespace cairn::sim {
namespace {

struct Ping {
  int value{0};
};

TEST(SimOutputsTest, ReadingsAreGroupedBySensorInTheOrderSensorsFirstProduced) {
  SimOutputs out;
  EXPECT_TRUE(out.empty());
  EXPECT_TRUE(out.Get<Ping>("sonar").empty());  // nothing yet: empty, no group made
  EXPECT_TRUE(out.groups().empty());
  out.Add("sonar", Ping{1});
  out.Add("depth", 2.5);
  out.Add("sonar", Ping{3});
  ASSERT_EQ(out.groups().size(), 2u);
  EXPECT_EQ(out.groups()[0]->sensor(), "sonar");
  EXPECT_EQ(out.groups()[1]->sensor(), "depth");
  ASSERT_EQ(out.Get<Ping>("sonar").size(), 2u);
  EXPECT_EQ(out.Get<Ping>("sonar")[1].value, 3);
  EXPECT_EQ(out.Get<double>("depth").front(), 2.5);
  EXPECT_EQ(out.groups()[0]->As<double>(), nullptr);  // asked as another type
  EXPECT_FALSE(out.empty());
}

TEST(SimOutputsTest, ClearKeepsTheGroupsAndEventsCount) {
  SimOutputs out;
  out.Add("sonar", Ping{1});
  out.Clear();
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(out.groups().size(), 1u);
  EXPECT_TRUE(out.Get<Ping>("sonar").empty());
  out.events.push_back("watchdog");
  EXPECT_FALSE(out.empty());
  // Readings can be moved out.
  out.Add("sonar", Ping{7});
  std::vector<Ping> taken = std::move(out.Mutable<Ping>("sonar"));
  EXPECT_EQ(taken.size(), 1u);
}

TEST(SimOutputsDeathTest, AskingForTheWrongTypeIsABug) {
  SimOutputs out;
  out.Add("sonar", Ping{1});
  EXPECT_DEATH(out.Get<double>("sonar"), "readings != nullptr");
}

}  // namespace
}  // namespace cairn::sim
