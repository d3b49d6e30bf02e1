// CostMap with the directed layer (one-way steps): the crossing rule, MotionAllowed against a
// brute-force reading, validity and cost of one-way cells, and directed connectivity.

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "common/layers.h"
#include "planner/cost_map.h"
#include "tests/unit/planner/test_maps.h"

namespace cairn::planner {
namespace {

using common::Pose2;
using common::Vector2;
using testing::DirectedTestLayer;
using testing::PioneerFootprint;

constexpr double kEighth = M_PI / 4;

TEST(HeadingClassTest, AxesExactlyAndOpenQuadrants) {
  EXPECT_EQ(HeadingClass(0.0), 0);
  EXPECT_EQ(HeadingClass(1e-9), 0);  // within the axis tolerance
  EXPECT_EQ(HeadingClass(-1e-9), 0);
  EXPECT_EQ(HeadingClass(0.3), 1);
  EXPECT_EQ(HeadingClass(kEighth), 1);
  EXPECT_EQ(HeadingClass(M_PI / 2), 2);
  EXPECT_EQ(HeadingClass(2.0), 3);
  EXPECT_EQ(HeadingClass(M_PI), 4);
  EXPECT_EQ(HeadingClass(-M_PI), 4);
  EXPECT_EQ(HeadingClass(-2.0), 5);
  EXPECT_EQ(HeadingClass(-M_PI / 2), 6);
  EXPECT_EQ(HeadingClass(-0.1), 7);
  EXPECT_EQ(HeadingClass(2.0 * M_PI - 0.1), 7);
  // Even: the bit of the axis alone; odd: the diagonal and both axes around it.
  EXPECT_EQ(HeadingClassBits(0), 0b00000001);
  EXPECT_EQ(HeadingClassBits(2), 0b00000100);
  EXPECT_EQ(HeadingClassBits(1), 0b00000111);
  EXPECT_EQ(HeadingClassBits(7), 0b11000001);
  EXPECT_EQ(HeadingClassBits(5), 0b01110000);
  EXPECT_EQ(HeadingStep(3).ix, -1);
  EXPECT_EQ(HeadingStep(3).iy, 1);
}

// An 8 cm step through (5, 5) rising towards heading k * 45 deg, k = 0..7 (the step line is
// straight for even k and a staircase for odd k), for the Pioneer (up 3 cm, down 10 cm).
DirectedTestLayer StepTowards(int k) {
  DirectedTestLayer d(100, 100, 0.1);
  d.Step({5.0, 5.0}, k * kEighth, 0.08).Derive();
  return d;
}

Pose2 At(const Vector2& p, double yaw) { return {p.x(), p.y(), yaw}; }

TEST(CostMapDirectedTest, AOneWayStepSeenFromEachOfEightHeadings) {
  for (int k = 0; k < 8; ++k) {
    SCOPED_TRACE("uphill towards bin " + std::to_string(k));
    const DirectedTestLayer d = StepTowards(k);
    const auto map = d.Build(PioneerFootprint());
    const double up = k * kEighth;
    const Vector2 u(std::cos(up), std::sin(up));
    const Vector2 low = Vector2(5.0, 5.0) - 0.5 * u;
    const Vector2 high = Vector2(5.0, 5.0) + 0.5 * u;
    ASSERT_GT(map->one_way_cells(), 0);
    // Astride the step the footprint is valid (one-way cells do not block poses) ...
    ASSERT_TRUE(map->IsValid(At(low, up)));
    ASSERT_TRUE(map->IsValid(At(high, up)));
    // ... where the cost layer alone has it lethal.
    const auto isotropic = d.layer.Build(PioneerFootprint());
    EXPECT_FALSE(isotropic->IsValid(At({5.0, 5.0}, up)));
    EXPECT_TRUE(map->IsValid(At({5.0, 5.0}, up)));
    EXPECT_TRUE(isotropic->MotionAllowed(At(low, up), At(high, up)));
    // Up: refused, forwards or reversing, straight or 30 deg oblique.
    EXPECT_FALSE(map->MotionAllowed(At(low, up), At(high, up)));
    EXPECT_FALSE(map->MotionAllowed(At(low, up + M_PI), At(high, up + M_PI)));  // reversing
    for (const double off : {-0.5, 0.5}) {
      const Vector2 w(std::cos(up + off), std::sin(up + off));
      const Vector2 from = Vector2(5.0, 5.0) - 0.5 * w;
      EXPECT_FALSE(map->MotionAllowed(At(from, up + off), At(from + w, up + off))) << off;
    }
    // Down: allowed, forwards or reversing, straight or 30 deg oblique.
    EXPECT_TRUE(map->MotionAllowed(At(high, up + M_PI), At(low, up + M_PI)));
    EXPECT_TRUE(map->MotionAllowed(At(high, up), At(low, up)));  // reversing down
    for (const double off : {-0.5, 0.5}) {
      const Vector2 w(std::cos(up + M_PI + off), std::sin(up + M_PI + off));
      const Vector2 from = Vector2(5.0, 5.0) - 0.5 * w;
      EXPECT_TRUE(map->MotionAllowed(At(from, up + M_PI + off), At(from + w, up + M_PI + off)))
          << off;
    }
    // Turning on the spot crosses nothing.
    EXPECT_TRUE(map->MotionAllowed(At(low, up), At(low, up + 2.0)));
    // Far from the step anything goes.
    const Vector2 far = Vector2(5.0, 5.0) + 3.0 * u;  // on the platform, along the step
    const Vector2 along(-u.y(), u.x());
    EXPECT_TRUE(map->MotionAllowed(At(far, 0.0), At(far + along, 0.0)));
  }
}

TEST(CostMapDirectedTest, DrivingAlongAStraightStepAstrideItIsAllowed) {
  const auto map = StepTowards(0).Build(PioneerFootprint());  // step line x = 5, up towards +x
  EXPECT_TRUE(map->MotionAllowed({5.0, 3.0, M_PI / 2}, {5.0, 7.0, M_PI / 2}));
  EXPECT_TRUE(map->MotionAllowed({5.0, 7.0, -M_PI / 2}, {5.0, 3.0, -M_PI / 2}));
  // Drifting up by 1 cm over 4 m is climbing all the same.
  EXPECT_FALSE(map->MotionAllowed({5.0, 3.0, M_PI / 2}, {5.01, 7.0, M_PI / 2}));
  EXPECT_TRUE(map->MotionAllowed({5.0, 3.0, M_PI / 2}, {4.99, 7.0, M_PI / 2}));
}

// A robot standing astride a one-way edge (both of its cells under the footprint, as when the
// map marks a step under a robot already on it) may drive on over it; one short of the edge
// may not, and the edge's other refusals hold.
TEST(CostMapDirectedTest, ARobotAstrideAOneWayEdgeMayDriveOnOverIt) {
  const auto map = StepTowards(0).Build(PioneerFootprint());  // step line x = 5, up towards +x
  const Pose2 astride{5.0, 5.0, 0.0};
  const auto straddled = map->StraddledOneWayBits(astride);
  ASSERT_FALSE(straddled.empty());
  for (const auto& s : straddled) EXPECT_EQ(s.bits & 1u, 1u) << "bit 0: up towards +x";
  const Pose2 ahead{5.6, 5.0, 0.0};
  EXPECT_FALSE(map->MotionAllowed(astride, ahead));
  EXPECT_TRUE(map->MotionAllowed(astride, ahead, FootprintKind::kRobot, straddled));
  // The Pioneer's front a cell short of the step line: nothing straddled, the climb refused.
  const Pose2 short_of{5.0 - 0.315 - 0.15, 5.0, 0.0};
  const auto none = map->StraddledOneWayBits(short_of);
  EXPECT_TRUE(none.empty());
  EXPECT_FALSE(map->MotionAllowed(short_of, ahead, FootprintKind::kRobot, none));
  // Straddled bits do not lend themselves to the same edge elsewhere: from astride at y = 5,
  // a climb 2 m along the step is refused.
  EXPECT_FALSE(
      map->MotionAllowed({5.0 - 0.5, 7.0, 0.0}, {5.6, 7.0, 0.0}, FootprintKind::kRobot, straddled));
}

// MotionAllowed's reading (skipping stretches the distance fields prove clear) agrees with
// rasterising the footprint at every sample.
bool BruteForceAllowed(const CostMap& map, const Pose2& from, const Pose2& to) {
  const Vector2 a = map.ToGridCells(from.position());
  const Vector2 d = map.ToGridCells(to.position()) - a;
  if (d.norm() < 1e-9) return true;
  const uint8_t bits = HeadingClassBits(HeadingClass(std::atan2(d.y(), d.x())));
  const double turn = common::WrapAngle(to.yaw_rad - from.yaw_rad);
  const double sweep =
      d.norm() + map.footprint().circumscribed_radius_m() / map.resolution_m() * std::abs(turn);
  const int n = std::max(1, static_cast<int>(std::ceil(sweep / 0.5)));
  std::vector<RowSpan> spans;
  for (int k = 0; k <= n; ++k) {
    const double t = static_cast<double>(k) / n;
    const Vector2 p = a + d * t;
    map.footprint().Rasterize(p.x(), p.y(), map.ToGridYaw(from.yaw_rad) + t * turn,
                              map.resolution_m(), &spans);
    for (const RowSpan& s : spans) {
      for (int ix = s.ix_min; ix <= s.ix_max; ++ix) {
        if (map.OneWayMask({ix, s.iy}) & bits) return false;
      }
    }
  }
  return true;
}

TEST(CostMapDirectedTest, MotionAllowedAgreesWithBruteForce) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> pos(0.5, 9.5), yaw(-M_PI, M_PI), len(0.0, 1.5);
  for (const int k : {0, 1, 6}) {
    const auto map = StepTowards(k).Build(PioneerFootprint());
    int refused = 0;
    for (int trial = 0; trial < 3000; ++trial) {
      const Pose2 from{pos(rng), pos(rng), yaw(rng)};
      const double heading = yaw(rng), length = len(rng);
      const Pose2 to{from.x_m + length * std::cos(heading), from.y_m + length * std::sin(heading),
                     from.yaw_rad + 0.5 * yaw(rng)};
      const bool brute = BruteForceAllowed(*map, from, to);
      ASSERT_EQ(map->MotionAllowed(from, to), brute)
          << "bin " << k << " from (" << from.x_m << ", " << from.y_m << ", " << from.yaw_rad
          << ") to (" << to.x_m << ", " << to.y_m << ", " << to.yaw_rad << ")";
      refused += brute ? 0 : 1;
    }
    EXPECT_GT(refused, 100) << "the trials reach the step";
  }
}

TEST(CostMapDirectedTest, OneWayCellsCostAndTheOtherMaskValues) {
  testing::TestLayer layer(50, 50, 0.1);
  layer.cost(9, 9) = layer.cost(19, 19) = layer.cost(29, 29) = 100.0f;
  layer.cost(39, 9) = NAN;
  common::Layer directed = common::Layer::Zero(50, 50);
  directed(9, 9) = 1.0f;      // (0.95, 0.95): one-way (may not leave towards +x)
  directed(19, 19) = 255.0f;  // (1.95, 1.95): every heading blocked
  directed(29, 29) = 3.5f;    // not a whole number: blocked
  directed(39, 9) = 4.0f;     // one-way but unknown
  directed(5, 40) = 7.0f;     // one-way on a free cell (layers out of step): graded
  directed(6, 40) = NAN;
  CostMapParams params;
  params.one_way_cost = 80.0f;
  const CostMap map(layer.geometry, layer.cost, directed, testing::SmallFootprint(), params);
  EXPECT_TRUE(map.has_directed());
  EXPECT_EQ(map.one_way_cells(), 3);
  EXPECT_EQ(map.OneWayMask({9, 9}), 1);
  EXPECT_EQ(map.OneWayMask({19, 19}), 0);
  EXPECT_EQ(map.OneWayMask({-1, 9}), 0);
  EXPECT_FLOAT_EQ(map.cost()(9, 9), 80.0f);
  EXPECT_FLOAT_EQ(map.cost()(5, 40), 80.0f);
  EXPECT_TRUE(std::isnan(map.cost()(39, 9)));
  EXPECT_FLOAT_EQ(map.cost()(19, 19), 100.0f);
  EXPECT_FLOAT_EQ(map.cost()(29, 29), 100.0f);
  const FootprintCost on_one_way = map.CheckFootprint({0.95, 0.95, 0.0});
  EXPECT_TRUE(on_one_way.valid);
  EXPECT_FLOAT_EQ(on_one_way.max_cost, 80.0f);
  EXPECT_FALSE(map.IsValid({1.95, 1.95, 0.0}));
  EXPECT_FALSE(map.IsValid({2.95, 2.95, 0.0}));
  // Leaving the one-way cell towards +x is refused, towards +y allowed.
  EXPECT_FALSE(map.MotionAllowed({0.9, 0.95, 0.0}, {1.2, 0.95, 0.0}));
  EXPECT_TRUE(map.MotionAllowed({0.95, 0.9, 0.0}, {0.95, 1.2, 0.0}));
  // A one-way cost at or above lethal reads as the highest graded cost.
  params.one_way_cost = 150.0f;
  const CostMap high(layer.geometry, layer.cost, directed, testing::SmallFootprint(), params);
  EXPECT_LT(high.cost()(9, 9), 100.0f);
  EXPECT_TRUE(high.IsValid({0.95, 0.95, 0.0}));
  // Another size is refused; no directed layer reads the cost layer alone.
  EXPECT_THROW(
      CostMap(layer.geometry, layer.cost, common::Layer::Zero(3, 3), testing::SmallFootprint()),
      std::invalid_argument);
  const CostMap plain(layer.geometry, layer.cost, std::nullopt, testing::SmallFootprint());
  EXPECT_FALSE(plain.has_directed());
  EXPECT_EQ(plain.one_way_cells(), 0);
  EXPECT_FALSE(plain.IsValid({0.95, 0.95, 0.0}));
  EXPECT_TRUE(plain.MotionAllowed({0.9, 0.95, 0.0}, {1.2, 0.95, 0.0}));
}

TEST(CostMapDirectedTest, ConnectivityFollowsTheOneWaySteps) {
  const auto closed = testing::OneWayStepCorridor().Build(PioneerFootprint());
  EXPECT_TRUE(closed->MaybeConnected({9.0, 2.0}, {3.0, 2.0}));   // down the step
  EXPECT_FALSE(closed->MaybeConnected({3.0, 2.0}, {9.0, 2.0}));  // up it: no way
  const auto ramp = testing::OneWayStepCorridor(3.5).Build(PioneerFootprint());
  EXPECT_TRUE(ramp->MaybeConnected({9.0, 2.0}, {3.0, 2.0}));
  EXPECT_TRUE(ramp->MaybeConnected({3.0, 2.0}, {9.0, 2.0}));  // round by the ramp
}

TEST(CostMapDirectedTest, OneWayClearanceIsTheDistanceToTheNearestOneWayCell) {
  const auto closed = testing::OneWayStepCorridor().Build(PioneerFootprint());
  ASSERT_GT(closed->one_way_cells(), 0);
  // The brute-force distance to the nearest one-way cell's centre, at cell centres.
  const common::GridGeometry& g = closed->geometry();
  for (const Vector2& p : {Vector2(2.05, 2.05), Vector2(5.25, 1.05), Vector2(9.95, 3.05)}) {
    double nearest = std::numeric_limits<double>::infinity();
    for (int iy = 0; iy < g.size_y; ++iy) {
      for (int ix = 0; ix < g.size_x; ++ix) {
        if (closed->OneWayMask({ix, iy}) != 0) {
          nearest = std::min(nearest, (g.CenterOf({ix, iy}) - p).norm());
        }
      }
    }
    EXPECT_NEAR(closed->SmoothOneWayClearanceAt(p), nearest, 0.02) << p.transpose();
  }
  // Without one-way cells, nothing is near.
  const auto isotropic = testing::OneWayStepCorridor().layer.Build(PioneerFootprint());
  EXPECT_TRUE(std::isinf(isotropic->SmoothOneWayClearanceAt({2.05, 2.05})));
}

// A rim marked as an unseen drop (layers::kUnseenDrop) with unknown ground beyond it at +x,
// read as a look-out (unseen_drop_is_unknown): a plan may lead over it towards the unknown
// ground, to look, and never from there back up over it. Read strictly it blocks both ways; with
// no unknown neighbour it reads as unknown ground.
TEST(CostMapDirectedTest, AnUnseenDropRimIsALookOutOnlyTowardsTheUnseenGround) {
  DirectedTestLayer d(120, 40, 0.1);
  d.layer.Rect(0.0, 0.0, 12.0, 0.3, 100.0f).Rect(0.0, 3.7, 12.0, 4.0, 100.0f);
  d.Derive();
  auto mark_rim = [&](bool unknown_beyond) {
    for (int iy = 3; iy < 37; ++iy) {
      d.layer.cost(59, iy) = 100.0f;
      d.directed(59, iy) = layers::kUnseenDrop;
      d.layer.cost(60, iy) = unknown_beyond ? NAN : 0.0f;
      d.directed(60, iy) = unknown_beyond ? NAN : 0.0f;
    }
  };
  mark_rim(true);
  CostMapParams params;
  params.unknown_is_traversable = true;
  const auto strict = d.Build(PioneerFootprint(), params);
  EXPECT_FALSE(strict->MaybeConnected({3.0, 2.0}, {9.0, 2.0}));
  EXPECT_FALSE(strict->MaybeConnected({9.0, 2.0}, {3.0, 2.0}));
  params.unseen_drop_is_unknown = true;
  const auto look = d.Build(PioneerFootprint(), params);
  EXPECT_EQ(look->unseen_drop_cells(), 34);
  EXPECT_EQ(look->one_way_cells(), 34);
  EXPECT_TRUE(look->MaybeConnected({3.0, 2.0}, {9.0, 2.0}));   // over the rim, to look
  EXPECT_FALSE(look->MaybeConnected({9.0, 2.0}, {3.0, 2.0}));  // up from the unseen side: never
  EXPECT_FALSE(look->MotionAllowed({6.3, 2.0, M_PI}, {5.7, 2.0, M_PI}));
  EXPECT_TRUE(look->MotionAllowed({5.7, 2.0, 0.0}, {6.3, 2.0, 0.0}));
  mark_rim(false);
  const auto seen = d.Build(PioneerFootprint(), params);
  EXPECT_TRUE(std::isnan(seen->cost()(59, 20)));
  EXPECT_TRUE(seen->MaybeConnected({9.0, 2.0}, {3.0, 2.0}));
}

// The horizon search follows the one-way steps too: a goal up the step is not reachable however
// far the horizon reaches, one down it is.
TEST(CostMapDirectedTest, TheHorizonSearchFollowsTheOneWaySteps) {
  const auto closed = testing::OneWayStepCorridor().Build(PioneerFootprint());
  EXPECT_TRUE(closed->ConnectedWithinHorizon({9.0, 2.0}, {3.0, 2.0}, 50.0, 1.0));
  EXPECT_FALSE(closed->ConnectedWithinHorizon({3.0, 2.0}, {9.0, 2.0}, 50.0, 1.0));
  const auto ramp = testing::OneWayStepCorridor(3.5).Build(PioneerFootprint());
  EXPECT_TRUE(ramp->ConnectedWithinHorizon({3.0, 2.0}, {9.0, 2.0}, 50.0, 1.0));
}

}  // namespace
}  // namespace cairn::planner
