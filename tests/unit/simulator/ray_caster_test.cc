#include "simulator/ray_caster.h"

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "simulator/mujoco_model.h"
#include "simulator/sensors/lidar_sensor.h"

namespace cairn::sim {
namespace {

// Every primitive MuJoCo 2.2 ray-casts, rotated, plus a height field and a transparent geom.
constexpr char kScene[] = R"(<mujoco>
  <asset>
    <hfield name="bumps" nrow="3" ncol="3" size="2 2 0.5 0.1"/>
  </asset>
  <worldbody>
    <geom type="plane" size="30 30 0.1"/>
    <geom type="box" size="0.5 2 1" pos="6 0 1" euler="0 0 30"/>
    <geom type="box" size="3 0.1 0.8" pos="0 7 0.8"/>
    <geom type="cylinder" size="0.4 1.2" pos="-5 2 1.2"/>
    <geom type="sphere" size="0.7" pos="-3 -5 0.7"/>
    <geom type="capsule" size="0.3 1" pos="3 -4 0.5" euler="90 0 0"/>
    <geom type="ellipsoid" size="1 0.5 0.3" pos="-6 -3 1" euler="10 20 30"/>
    <geom type="box" size="1 1 1" pos="0 -9 3" euler="45 45 0"/>
    <geom type="hfield" hfield="bumps" pos="9 9 0"/>
    <geom type="box" size="1 1 1" pos="0 3 1" rgba="1 1 1 0"/>
    <geom type="box" size="1 1 1" pos="2 3 1" group="4"/>
    <body pos="0 0 5"><freejoint/><geom type="box" size="0.3 0.3 0.3" group="1"/></body>
  </worldbody>
</mujoco>)";

class RayCasterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    InstallMujocoLogHooks();
    model_ = LoadModelFromText(kScene, "/tmp/ray_scene.xml");
    data_.reset(mj_makeData(model_.get()));
    // Fill the height field with a ramp so it is not flat.
    for (int i = 0; i < 9; ++i) model_->hfield_data[i] = static_cast<float>(i) / 8.f;
    mj_forward(model_.get(), data_.get());
    scene_ = std::make_unique<RayScene>(model_.get());
    scene_->Update(data_.get());
  }

  MjModelPtr model_;
  MjDataPtr data_;
  std::unique_ptr<RayScene> scene_;
};

// Rays are cast two at a time, or four where the processor has AVX2: every width it has.
std::vector<int> LanesToTest() {
  std::vector<int> lanes = {2};
  if (RayCaster::MostLanes() > 2) lanes.push_back(RayCaster::MostLanes());
  return lanes;
}

TEST(RayCasterLanesTest, TwoLanesAlwaysAndFourOnlyWithAvx2) {
  EXPECT_EQ(RayCaster(nullptr, 2).lanes(), 2);
  EXPECT_EQ(RayCaster(nullptr, 4).lanes(), RayCaster::MostLanes());
  EXPECT_EQ(RayCaster().lanes(), RayCaster::MostLanes());
  EXPECT_TRUE(RayCaster::MostLanes() == 2 || RayCaster::MostLanes() == 4);
}

TEST_F(RayCasterTest, MatchesMjRayEverywhere) {
  LidarParams lidar;
  lidar.azimuth_steps = 720;
  lidar.slices_per_revolution = 8;
  const RayPattern pattern = BuildLidarPattern(lidar).rays;
  for (const int lanes : LanesToTest()) {
    SCOPED_TRACE(std::to_string(lanes) + " lanes");
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> xy(-8.0, 8.0), z(0.2, 2.5), angle(-0.5, 0.5);
    RayCaster caster(nullptr, lanes);
    std::vector<RayHit> fast(pattern.directions.size()), reference(pattern.directions.size());
    int64_t hits = 0;
    for (int trial = 0; trial < 12; ++trial) {
      const Eigen::Vector3d origin(xy(rng), xy(rng), z(rng));
      const Eigen::Matrix3d rotation =
          (Eigen::AngleAxisd(angle(rng) * 6, Eigen::Vector3d::UnitZ()) *
           Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitY()) *
           Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitX()))
              .toRotationMatrix();
      const int groups = static_cast<int>(pattern.groups.size());
      caster.Cast(*scene_, data_.get(), origin, rotation, pattern, 0, groups, 40.0, -1,
                  fast.data());
      RayCaster::CastWithMjRay(model_.get(), data_.get(), origin, rotation, pattern, 0, groups,
                               40.0, reference.data());
      for (size_t i = 0; i < fast.size(); ++i) {
        ASSERT_EQ(fast[i].geom, reference[i].geom) << "trial " << trial << " ray " << i;
        if (reference[i].geom >= 0) {
          ASSERT_NEAR(fast[i].range_m, reference[i].range_m, 1e-9);
          ++hits;
        }
      }
    }
    EXPECT_GT(hits, 100000);
  }
}

TEST_F(RayCasterTest, TwoThreadsGiveTheSameResult) {
  const RayPattern pattern = BuildLidarPattern(LidarParams{}).rays;
  ThreadPool pool(2);
  RayCaster single, parallel(&pool);
  std::vector<RayHit> a(pattern.directions.size()), b(pattern.directions.size());
  const Eigen::Vector3d origin(1.0, -1.0, 0.6);
  const int groups = static_cast<int>(pattern.groups.size());
  single.Cast(*scene_, data_.get(), origin, Eigen::Matrix3d::Identity(), pattern, 0, groups, 70.0,
              -1, a.data());
  parallel.Cast(*scene_, data_.get(), origin, Eigen::Matrix3d::Identity(), pattern, 0, groups, 70.0,
                -1, b.data());
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].geom, b[i].geom);
    ASSERT_EQ(a[i].range_m, b[i].range_m);
  }
}

// A lidar casts one slice at a time into a buffer of just that slice (hits_base: its first ray):
// the same hits as casting into a buffer of the whole revolution, and nothing written outside.
TEST_F(RayCasterTest, SliceSizedBuffersGiveTheSameHits) {
  LidarParams lidar;
  lidar.azimuth_steps = 720;
  lidar.slices_per_revolution = 8;
  const LidarPattern layout = BuildLidarPattern(lidar);
  const RayPattern& pattern = layout.rays;
  RayCaster caster;
  const Eigen::Vector3d origin(1.0, -1.0, 0.6);
  std::vector<RayHit> full(pattern.directions.size());
  const int groups = static_cast<int>(pattern.groups.size());
  caster.Cast(*scene_, data_.get(), origin, Eigen::Matrix3d::Identity(), pattern, 0, groups, 40.0,
              -1, full.data());
  int64_t hits = 0;
  for (int s = 0; s < lidar.slices_per_revolution; ++s) {
    const int first = layout.slice_ray_begin[s], last = layout.slice_ray_begin[s + 1];
    // One guard entry on each side must stay untouched.
    std::vector<RayHit> slice(last - first + 2, RayHit{-7.0, -7});
    caster.Cast(*scene_, data_.get(), origin, Eigen::Matrix3d::Identity(), pattern,
                layout.slice_group_begin[s], layout.slice_group_begin[s + 1], 40.0, -1,
                slice.data() + 1, first);
    EXPECT_EQ(slice.front().geom, -7);
    EXPECT_EQ(slice.back().geom, -7);
    for (int i = first; i < last; ++i) {
      ASSERT_EQ(slice[i - first + 1].geom, full[i].geom) << "ray " << i;
      ASSERT_EQ(slice[i - first + 1].range_m, full[i].range_m) << "ray " << i;
      hits += full[i].geom >= 0 ? 1 : 0;
    }
  }
  EXPECT_GT(hits, 1000);
}

TEST(SharedLidarPatternTest, SharedByEqualLayoutsOnly) {
  LidarParams a;
  LidarParams b = a;
  b.max_range_m = 30.0;  // not part of the layout
  LidarParams c = a;
  c.azimuth_steps = 900;
  const auto pa = SharedLidarPattern(a), pb = SharedLidarPattern(b), pc = SharedLidarPattern(c);
  EXPECT_EQ(pa.get(), pb.get());
  EXPECT_NE(pa.get(), pc.get());
  const LidarPattern built = BuildLidarPattern(c);
  ASSERT_EQ(pc->rays.directions.size(), built.rays.directions.size());
  EXPECT_EQ(pc->slice_ray_begin, built.slice_ray_begin);
  EXPECT_EQ(pc->ring, built.ring);
  for (size_t i = 0; i < built.rays.directions.size(); ++i) {
    ASSERT_EQ(pc->rays.directions[i], built.rays.directions[i]);
  }
}

// Rays are cast in packets: a planar fan (each ray warmed by the one before, in the same packet)
// whose groups end in short packets, and the same fan without its component
// arrays (directions gathered ray by ray) give mj_ray's hits, ray for ray.
TEST_F(RayCasterTest, FansWithShortLastPacketsAndGatheredDirectionsMatchMjRay) {
  for (const int lanes : LanesToTest()) {
    SCOPED_TRACE(std::to_string(lanes) + " lanes");
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> xy(-8.0, 8.0), z(0.2, 2.5), angle(-0.5, 0.5);
    RayCaster caster(nullptr, lanes);
    int64_t hits = 0;
    for (const int beams : {361, 362, 363, 364, 7}) {
      RayPattern pattern;
      for (int i = 0; i < beams; ++i) {
        const double a = -M_PI + 2.0 * M_PI * i / beams;
        // Tilted a little so that the fan meets the floor, the tops of boxes and the planes' edges.
        pattern.directions.emplace_back(std::cos(a), std::sin(a), -0.15 + 0.3 * i / beams);
        pattern.directions.back().normalize();
      }
      pattern.BuildGroups(beams > 100 ? 17 : 3);
      RayPattern gathered = pattern;
      gathered.components.clear();
      const int groups = static_cast<int>(pattern.groups.size());
      const size_t n = pattern.directions.size();
      for (int trial = 0; trial < 6; ++trial) {
        const Eigen::Vector3d origin(xy(rng), xy(rng), z(rng));
        const Eigen::Matrix3d rotation =
            (Eigen::AngleAxisd(angle(rng) * 6, Eigen::Vector3d::UnitZ()) *
             Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitY()))
                .toRotationMatrix();
        std::vector<RayHit> fast(n), slow(n), reference(n);
        caster.Cast(*scene_, data_.get(), origin, rotation, pattern, 0, groups, 40.0, -1,
                    fast.data());
        caster.Cast(*scene_, data_.get(), origin, rotation, gathered, 0, groups, 40.0, -1,
                    slow.data());
        RayCaster::CastWithMjRay(model_.get(), data_.get(), origin, rotation, pattern, 0, groups,
                                 40.0, reference.data());
        for (size_t i = 0; i < n; ++i) {
          ASSERT_EQ(fast[i].geom, reference[i].geom)
              << beams << " beams, trial " << trial << " ray " << i;
          ASSERT_EQ(slow[i].geom, reference[i].geom)
              << beams << " beams, trial " << trial << " ray " << i;
          if (reference[i].geom >= 0) {
            ASSERT_NEAR(fast[i].range_m, reference[i].range_m, 1e-9);
            ASSERT_EQ(slow[i].range_m, fast[i].range_m);
            ++hits;
          }
        }
      }
    }
    EXPECT_GT(hits, 4000);  // of 8742 rays
  }
}

TEST_F(RayCasterTest, HiddenGeomsAndOwnersAreSkipped) {
  RayPattern pattern;
  pattern.directions = {Eigen::Vector3d(0, 1, 0)};  // towards the transparent box at y = 3
  pattern.BuildGroups(1);
  RayCaster caster;
  RayHit hit;
  const Eigen::Vector3d origin(0, 0, 1);
  caster.Cast(*scene_, data_.get(), origin, Eigen::Matrix3d::Identity(), pattern, 0, 1, 40.0, -1,
              &hit);
  // Through the transparent box (y 2..4) to the wall at y = 6.9.
  EXPECT_NEAR(hit.range_m, 6.9, 1e-9);
  // Marking the wall as owned by robot 0 hides it from robot 0 only.
  const int wall = 2;
  scene_->SetOwner(wall, 0);
  scene_->Update(data_.get());
  caster.Cast(*scene_, data_.get(), origin, Eigen::Matrix3d::Identity(), pattern, 0, 1, 40.0, 0,
              &hit);
  EXPECT_EQ(hit.geom, -1);
  caster.Cast(*scene_, data_.get(), origin, Eigen::Matrix3d::Identity(), pattern, 0, 1, 40.0, 1,
              &hit);
  EXPECT_EQ(hit.geom, wall);
  // A geom hidden at run time disappears for everyone.
  scene_->SetVisible(wall, false);
  scene_->Update(data_.get());
  caster.Cast(*scene_, data_.get(), origin, Eigen::Matrix3d::Identity(), pattern, 0, 1, 40.0, 1,
              &hit);
  EXPECT_EQ(hit.geom, -1);
}

}  // namespace
}  // namespace cairn::sim

namespace cairn::sim {
namespace {

// A rough 20 x 20 height field, rotated and raised, against MuJoCo's own mj_rayHfield, for
// rays from above the surface (where sensors are). Square, because mj_rayHfield's side-wall
// check indexes rows with the column count.
TEST(RayHeightFieldTest, MatchesMujocoOnRoughTerrain) {
  InstallMujocoLogHooks();
  MjModelPtr model = LoadModelFromText(R"(<mujoco>
    <asset><hfield name="terrain" nrow="20" ncol="20" size="6 4 1.5 0.3"/></asset>
    <worldbody><geom name="t" type="hfield" hfield="terrain" pos="1 -2 0.5" euler="0 0 25"/></worldbody>
  </mujoco>)",
                                       "/tmp/hfield_test.xml");
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> height(0.f, 1.f);
  for (int i = 0; i < 20 * 20; ++i) model->hfield_data[i] = height(rng);
  MjDataPtr data(mj_makeData(model.get()));
  mj_forward(model.get(), data.get());
  std::uniform_real_distribution<double> xy(-9.0, 9.0), above(0.02, 3.0), dir(-1.0, 1.0);
  int hits = 0, agree = 0, total = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    // An origin above the surface: the reference's own distance down from high up.
    double p[3] = {xy(rng), xy(rng), 10.0};
    const double down[3] = {0, 0, -1};
    const double drop = mj_rayHfield(model.get(), data.get(), 0, p, down);
    p[2] = (drop >= 0 ? 10.0 - drop : 0.0) + above(rng);
    Eigen::Vector3d v(dir(rng), dir(rng), dir(rng) - 0.3);
    v.normalize();
    const double vv[3] = {v.x(), v.y(), v.z()};
    const double ours = RayHeightField(model.get(), data.get(), 0, p, vv);
    const double theirs = mj_rayHfield(model.get(), data.get(), 0, p, vv);
    ++total;
    if (theirs >= 0) ++hits;
    if ((ours < 0) == (theirs < 0) && (ours < 0 || std::abs(ours - theirs) < 1e-9)) ++agree;
  }
  EXPECT_GT(hits, 3000);
  // Rays grazing a shared triangle edge may round either way: allow a handful.
  EXPECT_GE(agree, total - 5) << "of " << total;
}

}  // namespace
}  // namespace cairn::sim
