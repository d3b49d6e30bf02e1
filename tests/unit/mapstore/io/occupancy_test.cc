#include "mapstore/io/occupancy.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include <gtest/gtest.h>

#include "common/layers.h"
#include "tests/unit/mapstore/io/io_test_support.h"

namespace cairn::mapstore::io {
namespace {

using common::StatusCode;
using testing::Geometry;

TEST(OccupancyTest, OccupancyPercentConvertsLogOddsAndRefusesElevation) {
  common::GridMap map(Geometry(2, 1));
  map.AddLayer(layers::kOccupancyLogOdds) << 0.f, 2.f;
  map.AddLayer(layers::kElevation, 1.f);
  auto p = OccupancyPercent(map, layers::kOccupancyLogOdds);
  ASSERT_TRUE(p.ok());
  EXPECT_FLOAT_EQ((*p)(0, 0), 50.f);
  EXPECT_NEAR((*p)(1, 0), 88.08f, 0.01f);
  EXPECT_EQ(OccupancyPercent(map, layers::kElevation).status().code(),
            StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace cairn::mapstore::io
