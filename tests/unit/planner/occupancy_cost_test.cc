// Occupancy-to-cost conversion (Nav2 static layer with trinary_costmap off).

#include "planner/occupancy_cost.h"

#include <cmath>
#include <string>

#include <gtest/gtest.h>

namespace cairn::planner {
namespace {

// The message of the std::invalid_argument `f` throws ("" if none).
template <typename F>
std::string ThrownMessage(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(OccupancyCostTest, ThresholdsGradedBandAndUnknown) {
  OccupancyCostParams p;  // map_server's 65 / 25
  EXPECT_FLOAT_EQ(OccupancyToCost(100.f, p, 100.f), 100.f);
  EXPECT_FLOAT_EQ(OccupancyToCost(65.f, p, 100.f), 100.f);  // at the threshold: lethal
  EXPECT_FLOAT_EQ(OccupancyToCost(25.f, p, 100.f), 0.f);    // at the free threshold: free
  EXPECT_FLOAT_EQ(OccupancyToCost(0.f, p, 100.f), 0.f);
  EXPECT_FLOAT_EQ(OccupancyToCost(45.f, p, 100.f), 50.f);   // halfway: half the lethal cost
  EXPECT_FLOAT_EQ(OccupancyToCost(45.f, p, 254.f), 127.f);  // scales with the lethal cost
  const float just_below = OccupancyToCost(std::nextafter(65.f, 0.f), p, 100.f);
  EXPECT_LT(just_below, 100.f);  // graded cells are never lethal ...
  EXPECT_GT(OccupancyToCost(std::nextafter(25.f, 100.f), p, 100.f), 0.f);  // ... nor free
  EXPECT_TRUE(std::isnan(OccupancyToCost(-1.f, p, 100.f)));
  EXPECT_TRUE(std::isnan(OccupancyToCost(-50.f, p, 100.f)));
  EXPECT_TRUE(std::isnan(OccupancyToCost(NAN, p, 100.f)));
  EXPECT_FLOAT_EQ(OccupancyToCost(127.f, p, 100.f), 100.f);  // beyond 100 is occupied
}

TEST(OccupancyCostTest, MonotoneOverTheWholeRange) {
  OccupancyCostParams p;
  p.occupied_threshold_og = 20.f;
  p.free_threshold_og = 5.f;
  float previous = -1.f;
  for (int og = 0; og <= 100; ++og) {
    const float c = OccupancyToCost(static_cast<float>(og), p, 100.f);
    EXPECT_GE(c, previous) << og;
    EXPECT_EQ(c == 100.f, og >= 20) << og;
    EXPECT_EQ(c == 0.f, og <= 5) << og;
    previous = c;
  }
}

TEST(OccupancyCostTest, LayerConversionKeepsShapeAndUnknown) {
  common::Layer og(3, 2);
  og << 0.f, 50.f, 100.f, -1.f, NAN, 70.f;  // row-wise fill of a 3 x 2 matrix
  const common::Layer cost = OccupancyToCostLayer(og, OccupancyCostParams{}, 100.f);
  ASSERT_EQ(cost.rows(), 3);
  ASSERT_EQ(cost.cols(), 2);
  EXPECT_FLOAT_EQ(cost(0, 0), 0.f);
  EXPECT_FLOAT_EQ(cost(0, 1), 62.5f);  // 50: (50 - 25) / (65 - 25)
  EXPECT_FLOAT_EQ(cost(1, 0), 100.f);
  EXPECT_TRUE(std::isnan(cost(1, 1)));
  EXPECT_TRUE(std::isnan(cost(2, 0)));
  EXPECT_FLOAT_EQ(cost(2, 1), 100.f);
}

TEST(OccupancyCostTest, RefusesBadParams) {
  OccupancyCostParams p;
  p.free_threshold_og = 70.f;
  EXPECT_NE(ThrownMessage([&] { p.Validate(); }).find("must be below occupied_threshold_og"),
            std::string::npos);
  p = {};
  p.occupied_threshold_og = 120.f;
  EXPECT_NE(ThrownMessage([&] { p.Validate(); }).find("occupied_threshold_og"), std::string::npos);
  p = {};
  p.free_threshold_og = -1.f;
  EXPECT_NE(ThrownMessage([&] { p.Validate(); }).find("free_threshold_og"), std::string::npos);
  EXPECT_NE(ThrownMessage([] {
              OccupancyToCostLayer(common::Layer(1, 1), OccupancyCostParams{}, 0.f);
            }).find("lethal_cost"),
            std::string::npos);
  EXPECT_EQ(MapEncodingFromName("occupancy"), MapEncoding::kOccupancy);
  EXPECT_EQ(MapEncodingFromName("cost"), MapEncoding::kCost);
  EXPECT_NE(ThrownMessage([] { MapEncodingFromName("octomap"); }).find("octomap"),
            std::string::npos);
}

}  // namespace
}  // namespace cairn::planner
