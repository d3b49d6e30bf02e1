#include "simulator/sonar_model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

// Seed 004 §7 unit tests 1-7 and 10: the sweep, the bins, the echo profiles of analytic scenes
// (a flat seabed, a wall, a rock face and its shadow, the blind zone), robustness, the timing
// helper. The scenes are cast here in the fan's vertical plane: the sensor `height_m` above a
// flat seabed, a face from the seabed up to `face_height_m` at `face_x_m` ahead.

namespace cairn::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kInf = std::numeric_limits<double>::infinity();

struct Scene {
  double height_m{2.0};
  double face_x_m{kInf};
  double face_height_m{kInf};  // kInf: a wall higher than the fan reaches
};

std::vector<double> CastFan(const Scene& s, const SonarFanParams& p) {
  std::vector<double> r(p.rays);
  for (int i = 0; i < p.rays; ++i) {
    const double e = p.RayElevationRad(i);
    const double c = std::cos(e), sn = std::sin(e);
    double range = kInf;
    if (sn < 0.0) range = s.height_m / -sn;  // the seabed
    if (std::isfinite(s.face_x_m)) {
      const double t = s.face_x_m / c;       // where the ray crosses the face's plane
      const double z = s.height_m + t * sn;  // its height above the seabed there
      if (t < range && z >= 0.0 && z <= s.face_height_m) range = t;
    }
    r[i] = range;
  }
  return r;
}

SonarFanParams Faithful() {
  SonarFanParams p;
  p.model = SonarEchoModel::kFaithful;
  return p;
}

int FirstNonZero(const std::vector<uint8_t>& v) {
  for (size_t k = 0; k < v.size(); ++k) {
    if (v[k] != 0) return static_cast<int>(k);
  }
  return -1;
}

// Test 1: from 35 deg in 0.005 rad steps, the first reversal after 88 pings at 1.050865 rad,
// then one every 420 pings at -1.049135 and +1.050865 rad; the head never passes 1.050865 rad
// (60.21 deg), and Advance returns the angle after the step.
TEST(SonarSweepTest, Seed004Test1TheSectorSweepReversesAfter88ThenEvery420Pings) {
  SonarSweep sweep{SonarSweepParams{}};
  EXPECT_NEAR(sweep.angle_rad(), 35.0 * kDeg, 1e-12);
  std::vector<int64_t> at;
  std::vector<double> where;
  for (int64_t ping = 1; ping <= 88 + 5 * 420; ++ping) {
    const double before = sweep.angle_rad();
    const int64_t reversals = sweep.reversals();
    const double published = sweep.Advance();
    EXPECT_NEAR(std::abs(published - before), 0.005, 1e-12);
    EXPECT_EQ(published, sweep.angle_rad());
    ASSERT_LE(std::abs(published), 1.050865 + 1e-6);  // 60.21 deg
    if (sweep.reversals() != reversals) {
      at.push_back(ping);
      where.push_back(published);
    }
  }
  ASSERT_EQ(at.size(), 6u);
  EXPECT_EQ(at[0], 88);
  EXPECT_NEAR(where[0], 1.050865, 1e-6);
  for (size_t i = 1; i < at.size(); ++i) {
    EXPECT_EQ(at[i] - at[i - 1], 420) << i;
    EXPECT_NEAR(where[i], i % 2 ? -1.049135 : 1.050865, 1e-6) << i;
  }
}

// Test 2: 50 m in 1 m bins is 50 bins; in the thesis's model bin 49 is always 0, a ray at
// exactly 49.0 m is ignored and one at 48.99 m counts in bin 48.
TEST(SonarEchoTest, Seed004Test2FiftyBinsAndTheLastOneAlwaysEmpty) {
  SonarFanParams p = Faithful();
  EXPECT_EQ(p.NumBins(), 50);
  p.rays = 3;
  // Two rays on a face at 48.99 m and a third beyond it: bin 48 gets the first.
  auto profile = EchoProfile({48.99, 48.995, 49.0}, p);
  ASSERT_EQ(profile.size(), 50u);
  EXPECT_GT(profile[48], 0);
  EXPECT_EQ(profile[49], 0);
  // All at 49.0 m or beyond: nothing.
  profile = EchoProfile({49.0, 49.5, 49.99}, p);
  for (uint8_t v : profile) EXPECT_EQ(v, 0);
  // The default model uses the last bin too.
  p.model = SonarEchoModel::kGeometric;
  profile = EchoProfile({49.2, 49.3, 49.4}, p);
  EXPECT_GT(profile[49], 0);
}

// Test 3: over a flat seabed 2 m below, the first echo is bin 5 at about 81, then falling (75,
// 65, 58, 52, 47, ...), never above 87 (255 sin 20 deg): no obstacle. From 5 m up, bin 14.
TEST(SonarEchoTest, Seed004Test3AFlatSeabedNeverEchoesAbove87) {
  const SonarFanParams p = Faithful();
  const auto profile = EchoProfile(CastFan({2.0}, p), p);
  ASSERT_EQ(FirstNonZero(profile), 5);
  EXPECT_NEAR(profile[5], 81, 2);
  const int expected[] = {81, 75, 65, 58, 52, 47};
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(profile[5 + k], expected[k], 3) << "bin " << 5 + k;
  for (int k = 6; k < 49; ++k) {
    if (profile[k] != 0) {
      EXPECT_LE(profile[k], profile[k - 1]) << "bin " << k;
    }
  }
  EXPECT_LE(*std::max_element(profile.begin(), profile.end()), 87);
  const auto deeper = EchoProfile(CastFan({5.0}, p), p);
  EXPECT_EQ(FirstNonZero(deeper), 14);
  EXPECT_NEAR(deeper[14], 81, 2);
  // The default model agrees on the bound: grazing seabed stays under the detection's 110.
  SonarFanParams g;
  const auto geometric = EchoProfile(CastFan({2.0}, g), g);
  EXPECT_LE(*std::max_element(geometric.begin(), geometric.end()), 88);
  EXPECT_EQ(FirstNonZero(geometric), 5);
}

// Test 4: a wall 10 m ahead (2 m above the seabed) peaks at bin 10, at 240 or more.
TEST(SonarEchoTest, Seed004Test4AWallTenMetresAheadPeaksAtBinTen) {
  for (const SonarFanParams& p : {Faithful(), SonarFanParams{}}) {
    const auto profile = EchoProfile(CastFan({2.0, 10.0}, p), p);
    const auto peak = std::max_element(profile.begin(), profile.end());
    EXPECT_EQ(peak - profile.begin(), 10) << SonarEchoModelName(p.model);
    EXPECT_GE(*peak, 240) << SonarEchoModelName(p.model);
    for (int k = 11; k < 50; ++k) EXPECT_EQ(profile[k], 0) << "behind the wall, bin " << k;
  }
}

// Test 5: a 1.5 m face 15 m ahead, 5 m above the seabed: its peak at bin 15 (about 209-223),
// its shadow over bins 16-21, the seabed again from bin 22 (about 55).
TEST(SonarEchoTest, Seed004Test5ARockFaceCastsAShadowBehindItsPeak) {
  const SonarFanParams p = Faithful();
  const auto profile = EchoProfile(CastFan({5.0, 15.0, 1.5}, p), p);
  EXPECT_GE(profile[15], 200);
  EXPECT_LE(profile[15], 230);
  for (int k = 16; k <= 21; ++k) EXPECT_EQ(profile[k], 0) << "shadow, bin " << k;
  EXPECT_NEAR(profile[22], 55, 5);
  const SonarFanParams g;
  const auto geometric = EchoProfile(CastFan({5.0, 15.0, 1.5}, g), g);
  EXPECT_GE(geometric[15], 200);
  for (int k = 16; k <= 21; ++k) EXPECT_EQ(geometric[k], 0) << "shadow, bin " << k;
}

// Test 6: a 1 m face 8 m ahead, 5 m above the seabed, lies under the fan's lowest ray: only the
// seabed echoes (nothing above 87).
TEST(SonarEchoTest, Seed004Test6AFaceUnderTheFanIsInItsBlindZone) {
  for (const SonarFanParams& p : {Faithful(), SonarFanParams{}}) {
    const auto with_face = EchoProfile(CastFan({5.0, 8.0, 1.0}, p), p);
    const auto without = EchoProfile(CastFan({5.0}, p), p);
    EXPECT_EQ(with_face, without) << SonarEchoModelName(p.model);
    EXPECT_LE(*std::max_element(with_face.begin(), with_face.end()), 87);
  }
}

// Test 7: every ray hitting within 49 m (the thesis raised IndexError), rays at the same range
// (c = 0), asin arguments above 1, no returns at all, NaN ranges: a profile, never a crash.
TEST(SonarEchoTest, Seed004Test7AnyFanGivesAProfile) {
  for (const SonarFanParams& p : {Faithful(), SonarFanParams{}}) {
    const auto wall = EchoProfile(CastFan({2.0, 3.0}, p), p);
    EXPECT_EQ(wall.size(), 50u);
    std::vector<double> same(p.rays, 7.0);
    EXPECT_EQ(EchoProfile(same, p).size(), 50u);
    std::vector<double> odd(p.rays);
    for (int i = 0; i < p.rays; ++i) odd[i] = (i % 2) ? 0.5 : 40.0;  // asin argument > 1
    EXPECT_EQ(EchoProfile(odd, p).size(), 50u);
    std::vector<double> none(p.rays, kInf);
    for (uint8_t v : EchoProfile(none, p)) EXPECT_EQ(v, 0);
    std::vector<double> nan(p.rays, std::nan(""));
    for (uint8_t v : EchoProfile(nan, p)) EXPECT_EQ(v, 0);
    EXPECT_THROW(EchoProfile(std::vector<double>(10, 1.0), p), std::invalid_argument);
  }
}

// Test 10: eq. 2.1 as printed (e / v) and the round trip (2e / v); per bin with 50 bins.
TEST(SonarTimingTest, Seed004Test10PingAndBinTimes) {
  EXPECT_NEAR(PingTimeS(50.0, 1550.0, false), 0.03226, 1e-5);
  EXPECT_NEAR(PingTimeS(50.0, 1550.0, true), 0.06452, 1e-5);
  EXPECT_NEAR(BinTimeS(50.0, 1550.0, 50, false), 0.000645, 1e-6);
  EXPECT_NEAR(BinTimeS(50.0, 1550.0, 50, true), 0.00129, 1e-5);
}

TEST(SonarEchoTest, ParamsAreCheckedAndModelsNamed) {
  SonarFanParams p;
  EXPECT_NO_THROW(p.Validate());
  p.bin_m = 0.0;
  EXPECT_THROW(p.Validate(), std::invalid_argument);
  EXPECT_EQ(SonarEchoModelFromName("faithful"), SonarEchoModel::kFaithful);
  EXPECT_THROW(SonarEchoModelFromName("pretty"), std::invalid_argument);
  SonarSweepParams s;
  s.start_rad = 2.0;
  EXPECT_THROW(SonarSweep{s}, std::invalid_argument);
}

}  // namespace
}  // namespace cairn::sim
