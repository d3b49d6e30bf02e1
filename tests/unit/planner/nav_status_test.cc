#include "planner/nav_status.h"

#include <set>
#include <string>

#include <gtest/gtest.h>

namespace cairn::planner {
namespace {

TEST(NavStatusTest, ReasonsMapOneToOneOntoPlanStatus) {
  std::set<int> seen;
  for (const PlanStatus s :
       {PlanStatus::kSuccess, PlanStatus::kStartOccupied, PlanStatus::kGoalOccupied,
        PlanStatus::kOutOfBounds, PlanStatus::kNoPath, PlanStatus::kTimedOut,
        PlanStatus::kCancelled, PlanStatus::kApproximate}) {
    const NavReason r = ReasonOf(s);
    EXPECT_STREQ(NavReasonName(r), PlanStatusName(s));
    seen.insert(static_cast<int>(r));
  }
  EXPECT_EQ(seen.size(), 8u);
}

TEST(NavStatusTest, EveryStateAndReasonHasAName) {
  std::set<std::string> states;
  for (int s = 0; s <= 7; ++s) states.insert(NavStateName(static_cast<NavState>(s)));
  EXPECT_EQ(states.size(), 8u);
  EXPECT_EQ(states.count("UNKNOWN"), 0u);
  std::set<std::string> reasons;
  for (int r = 0; r <= 13; ++r) reasons.insert(NavReasonName(static_cast<NavReason>(r)));
  EXPECT_EQ(reasons.size(), 14u);
  EXPECT_EQ(reasons.count("UNKNOWN"), 0u);
  EXPECT_STREQ(NavStateName(NavState::kStopped), "STOPPED");
  EXPECT_STREQ(NavReasonName(NavReason::kStaleMap), "STALE_MAP");
}

}  // namespace
}  // namespace cairn::planner
