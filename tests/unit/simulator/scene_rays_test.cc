#include "simulator/scene_rays.h"

#include <vector>

#include <gtest/gtest.h>

#include "simulator/mujoco_model.h"
#include "simulator/sensors/planar_laser_sensor.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

using testing::FlatWorld;

class SceneRaysTest : public testing::SimTest {
 protected:
  void SetUp() override {
    SimTest::SetUp();
    // A grey floor, a white post 2 m ahead, a black one 4 m ahead behind it (hidden).
    model_ = LoadModelFromText(FlatWorld(R"(
        <geom name="white" type="box" size="0.1 0.1 1" pos="2.1 0 1" rgba="1 1 1 1"/>
        <geom name="black" type="box" size="0.1 0.1 1" pos="4.1 0 1" rgba="0 0 0 1"/>)"),
                               "/tmp/scene_rays_test.xml");
    data_.reset(mj_makeData(model_.get()));
    mj_forward(model_.get(), data_.get());
    white_ = mj_name2id(model_.get(), mjOBJ_GEOM, "white");
    black_ = mj_name2id(model_.get(), mjOBJ_GEOM, "black");
    sensor_.position_m = common::Vector3(0.0, 0.0, 0.5);
  }

  MjModelPtr model_;
  MjDataPtr data_;
  int white_{-1}, black_{-1};
  common::Pose3 sensor_;
};

TEST_F(SceneRaysTest, CastsCountsAndGivesIntensities) {
  SceneRays rays(model_.get(), 1);
  const RayPattern fan = BuildFanPattern(10.0, 11);  // the centre beam looks along x
  std::vector<RayHit> hits(fan.directions.size());
  rays.CastAll(data_.get(), 0, sensor_, fan, 30.0, &hits);
  EXPECT_EQ(hits[5].geom, white_);
  EXPECT_NEAR(hits[5].range_m, 2.0, 1e-12);
  EXPECT_EQ(rays.rays_cast(), 11);
  EXPECT_FLOAT_EQ(rays.intensity(white_), 100.f);
  EXPECT_FLOAT_EQ(rays.intensity(black_), 0.f);
  EXPECT_FLOAT_EQ(rays.intensities()[0], 50.f);  // the floor, 0.5 grey
  // The mj_ray baseline finds the same.
  std::vector<RayHit> reference(hits.size());
  rays.set_use_mj_ray(true);
  rays.CastAll(data_.get(), 0, sensor_, fan, 30.0, &reference);
  for (size_t i = 0; i < hits.size(); ++i) {
    EXPECT_EQ(reference[i].geom, hits[i].geom) << i;
    EXPECT_NEAR(reference[i].range_m, hits[i].range_m, 1e-9) << i;
  }
  EXPECT_EQ(rays.rays_cast(), 22);
}

TEST_F(SceneRaysTest, OwnGeomsAreUnseenAndMovesAreSeenAfterMarkMoved) {
  SceneRays rays(model_.get(), 1);
  rays.scene().SetOwner(white_, 3);  // robot 3's own body
  const RayPattern fan = BuildFanPattern(10.0, 11);
  std::vector<RayHit> hits(fan.directions.size());
  rays.CastAll(data_.get(), 3, sensor_, fan, 30.0, &hits);
  EXPECT_EQ(hits[5].geom, black_);  // robot 3 sees past itself
  rays.CastAll(data_.get(), 0, sensor_, fan, 30.0, &hits);
  EXPECT_EQ(hits[5].geom, white_);  // others see it
  // The black post moves 1 m closer; the caster's boxes follow once told.
  model_->geom_pos[3 * black_] = 3.1;
  mj_kinematics(model_.get(), data_.get());
  rays.MarkMoved();
  rays.CastAll(data_.get(), 3, sensor_, fan, 30.0, &hits);
  EXPECT_NEAR(hits[5].range_m, 3.0, 1e-12);
}

}  // namespace
}  // namespace cairn::sim
