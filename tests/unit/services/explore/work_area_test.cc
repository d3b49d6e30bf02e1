#include "services/explore/work_area.h"

#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace cairn::explore {
namespace {

std::string ValidationError(const WorkArea& area) {
  try {
    area.Validate();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(WorkAreaTest, ARectangleIsValidAndContainsItsInsideAndItsEdges) {
  const WorkArea area = RectangleWorkArea({0.0, 0.0}, {10.0, 5.0});
  EXPECT_EQ(ValidationError(area), "");
  EXPECT_TRUE(area.Contains({5.0, 2.5}));
  EXPECT_TRUE(area.Contains({10.0, 2.0}));
  EXPECT_TRUE(area.Contains({0.0, 0.0}));
  EXPECT_FALSE(area.Contains({10.1, 2.0}));
  EXPECT_FALSE(area.Contains({-0.1, -0.1}));
  EXPECT_DOUBLE_EQ(area.AreaM2(), 50.0);
}

TEST(WorkAreaTest, AConcavePolygonExcludesItsNotch) {
  // An L: the square (0..10)^2 without (5..10) x (5..10).
  const WorkArea area{{{0, 0}, {10, 0}, {10, 5}, {5, 5}, {5, 10}, {0, 10}}};
  EXPECT_EQ(ValidationError(area), "");
  EXPECT_TRUE(area.Contains({2, 8}));
  EXPECT_TRUE(area.Contains({8, 2}));
  EXPECT_FALSE(area.Contains({8, 8}));
  EXPECT_DOUBLE_EQ(area.AreaM2(), 75.0);
}

TEST(WorkAreaTest, AnEmptyOrDegenerateAreaIsRefusedWithTheReason) {
  EXPECT_NE(ValidationError(WorkArea{}).find("at least 3 vertices"), std::string::npos);
  EXPECT_NE(ValidationError(WorkArea{{{0, 0}, {1, 1}, {2, 2}}}).find("no area"), std::string::npos);
  EXPECT_NE(ValidationError(WorkArea{{{0, 0}, {0, 0}, {2, 2}}}).find("repeats"), std::string::npos);
  EXPECT_NE(ValidationError(WorkArea{{{0, 0}, {NAN, 0}, {2, 2}}}).find("not finite"),
            std::string::npos);
}

TEST(WorkAreaTest, ASelfIntersectingOutlineIsRefusedNamingTheEdges) {
  // A bow tie: edge 0 (0,0)-(4,4) crosses edge 2 (4,0)-(0,6).
  const std::string error = ValidationError(WorkArea{{{0, 0}, {4, 4}, {4, 0}, {0, 6}}});
  EXPECT_NE(error.find("edge 0 crosses edge 2"), std::string::npos) << error;
}

TEST(WorkAreaTest, ParsesVerticesAndRefusesBadTokens) {
  const WorkArea area = ParseWorkArea("-5,-5 5,-5 5,5 -5,5");
  ASSERT_EQ(area.vertices_m.size(), 4u);
  EXPECT_DOUBLE_EQ(area.vertices_m[2].x(), 5.0);
  EXPECT_DOUBLE_EQ(area.vertices_m[0].y(), -5.0);
  EXPECT_THROW(ParseWorkArea("1,2 3"), std::invalid_argument);
  EXPECT_THROW(ParseWorkArea("1,2 3,x"), std::invalid_argument);
  EXPECT_THROW(ParseWorkArea("1,2 3,4z"), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::explore
