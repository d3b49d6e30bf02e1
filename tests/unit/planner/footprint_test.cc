#include "planner/footprint.h"

#include <random>
#include <set>

#include <gtest/gtest.h>

#include "common/robot_profile.h"

namespace cairn::planner {
namespace {

using common::Vector2;

// Closed convex polygon vs closed axis-aligned unit square at (ix, iy): separating axis test.
bool Overlaps(const std::vector<Vector2>& poly, int ix, int iy) {
  std::vector<Vector2> square = {{double(ix), double(iy)},
                                 {ix + 1.0, double(iy)},
                                 {ix + 1.0, iy + 1.0},
                                 {double(ix), iy + 1.0}};
  std::vector<Vector2> axes = {{1, 0}, {0, 1}};
  for (size_t i = 0; i < poly.size(); ++i) {
    const Vector2 e = poly[(i + 1) % poly.size()] - poly[i];
    axes.emplace_back(-e.y(), e.x());
  }
  for (const Vector2& a : axes) {
    double p0 = 1e300, p1 = -1e300, s0 = 1e300, s1 = -1e300;
    for (const Vector2& v : poly) {
      p0 = std::min(p0, a.dot(v));
      p1 = std::max(p1, a.dot(v));
    }
    for (const Vector2& v : square) {
      s0 = std::min(s0, a.dot(v));
      s1 = std::max(s1, a.dot(v));
    }
    if (p1 < s0 - 1e-9 || s1 < p0 - 1e-9) return false;
  }
  return true;
}

TEST(FootprintTest, HullAndRadii) {
  // A concave polygon becomes its hull; duplicate and collinear points disappear.
  const std::vector<Vector2> poly = {{1, 1},  {0, 0.2}, {-1, 1}, {-1, -1},
                                     {0, -1}, {1, -1},  {1, -1}};
  const FootprintRasterizer r(poly);
  EXPECT_EQ(r.hull_m().size(), 4u);
  EXPECT_NEAR(r.circumscribed_radius_m(), std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(r.inscribed_radius_m(), 1.0, 1e-12);
  // Origin outside the footprint: no inscribed disc.
  const FootprintRasterizer off({{1, 1}, {2, 1}, {2, 2}, {1, 2}});
  EXPECT_EQ(off.inscribed_radius_m(), 0.0);
  EXPECT_THROW(FootprintRasterizer({{0, 0}, {1, 1}}), std::invalid_argument);
  EXPECT_THROW(FootprintRasterizer({{0, 0}, {1, 1}, {2, 2}}), std::invalid_argument);
  EXPECT_TRUE(PointInPolygon(poly, {0.5, 0.0}));
  EXPECT_FALSE(PointInPolygon(poly, {0.0, 0.8}));  // in the notch
}

TEST(FootprintTest, AxisAlignedRectangleCoversExactlyItsCells) {
  // 0.6 m × 0.4 m centred at (1.05, 1.05) on a 0.1 m grid covers x in [0.75, 1.35] and
  // y in [0.85, 1.25]: cells 7..13 in x and 8..12 in y.
  const FootprintRasterizer r(common::RectangleFootprint(0.6, 0.4));
  std::vector<RowSpan> spans;
  r.Rasterize(10.5, 10.5, 0.0, 0.1, &spans);
  ASSERT_EQ(spans.size(), 5u);
  for (size_t k = 0; k < spans.size(); ++k) {
    EXPECT_EQ(spans[k].iy, 8 + static_cast<int>(k));
    EXPECT_EQ(spans[k].ix_min, 7);
    EXPECT_EQ(spans[k].ix_max, 13);
  }
  // Turned by 90 degrees the spans swap.
  r.Rasterize(10.5, 10.5, M_PI / 2, 0.1, &spans);
  ASSERT_EQ(spans.size(), 7u);
  EXPECT_EQ(spans.front().iy, 7);
  EXPECT_EQ(spans.front().ix_min, 8);
  EXPECT_EQ(spans.front().ix_max, 12);
}

TEST(FootprintTest, RasterisationMatchesBruteForceOverlap) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> pos(5.0, 15.0), yaw(-M_PI, M_PI);
  const std::vector<std::vector<Vector2>> shapes = {
      common::RectangleFootprint(0.63, 0.5),
      {{0.4, 0.0}, {-0.2, 0.3}, {-0.3, -0.25}},
      {{0.3, 0.1}, {0.1, 0.3}, {-0.2, 0.25}, {-0.3, -0.1}, {0.0, -0.3}, {0.25, -0.2}}};
  const double res = 0.1;
  std::vector<RowSpan> spans;
  for (const auto& shape : shapes) {
    const FootprintRasterizer r(shape);
    for (int trial = 0; trial < 300; ++trial) {
      const double x = pos(rng), y = pos(rng), th = yaw(rng);
      r.Rasterize(x, y, th, res, &spans);
      std::set<std::pair<int, int>> got;
      for (const RowSpan& s : spans) {
        for (int ix = s.ix_min; ix <= s.ix_max; ++ix) got.insert({ix, s.iy});
      }
      // The polygon in cell units.
      std::vector<Vector2> poly;
      const double c = std::cos(th), sn = std::sin(th);
      for (const Vector2& v : r.hull_m()) {
        poly.emplace_back(x + (c * v.x() - sn * v.y()) / res, y + (sn * v.x() + c * v.y()) / res);
      }
      std::set<std::pair<int, int>> want;
      for (int iy = 0; iy < 25; ++iy) {
        for (int ix = 0; ix < 25; ++ix) {
          if (Overlaps(poly, ix, iy)) want.insert({ix, iy});
        }
      }
      ASSERT_EQ(got, want) << "trial " << trial << " at (" << x << ", " << y << ", " << th << ")";
    }
  }
}

}  // namespace
}  // namespace cairn::planner
