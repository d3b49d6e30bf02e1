#include "common/robot_profile.h"

#include <cmath>
#include <fstream>

#include <gtest/gtest.h>

namespace cairn::common {
namespace {

constexpr char kPioneer[] = R"(
name: pioneer3at
drive: skid_steer
length_m: 0.63
width_m: 0.5
max_slope_up_deg: 8
max_slope_down_rad: .inf
max_step_up_m: 0.03
max_step_down_m: 0.10
max_vel_x_mps: 0.7
sensors: [hdl32e, imu]
)";

TEST(RobotProfileTest, LoadsDegreesAndRectangle) {
  const RobotProfile p = LoadRobotProfileString(kPioneer);
  EXPECT_EQ(p.name, "pioneer3at");
  EXPECT_EQ(p.drive, DriveKind::kSkidSteer);
  EXPECT_NEAR(p.max_slope_up_rad, 8.0 * M_PI / 180.0, 1e-12);
  EXPECT_TRUE(std::isinf(p.max_slope_down_rad));
  ASSERT_EQ(p.footprint_m.size(), 4u);
  EXPECT_NEAR(p.CircumscribedRadius(), std::hypot(0.315, 0.25), 1e-12);
  EXPECT_NEAR(p.InscribedRadius(), 0.25, 1e-12);
  EXPECT_EQ(p.sensors, (std::vector<std::string>{"hdl32e", "imu"}));
}

TEST(RobotProfileTest, UnknownKeyNamesFileAndLine) {
  try {
    LoadRobotProfileString("name: x\nlength_m: 1\nwidth_m: 1\nmax_slope_upp_deg: 3\n", "p.yaml");
    FAIL() << "expected an error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("p.yaml:4"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("max_slope_upp_deg"), std::string::npos) << e.what();
  }
}

TEST(RobotProfileTest, InvalidValuesAreRefused) {
  EXPECT_THROW(LoadRobotProfileString("name: x\nlength_m: 1\nwidth_m: 1\nmax_step_up_m: -1\n"),
               ConfigError);
  EXPECT_THROW(LoadRobotProfileString("name: 'a b'\nlength_m: 1\nwidth_m: 1\n"), ConfigError);
  EXPECT_THROW(LoadRobotProfileString("name: x\nlength_m: 1\nwidth_m: 1\ndrive: hover\n"),
               ConfigError);
  // Issue 20 (found by fuzz_yaml_loaders): a footprint vertex that is not two numbers, or a key
  // that is not a name, escaped as yaml-cpp's BadConversion, without the file's name.
  try {
    LoadRobotProfileString("name: x\nfootprint_m: [[0, 0], [1, {a: 1}], [1, 1]]\n", "f.yaml");
    FAIL() << "expected an error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("f.yaml:2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(LoadRobotProfileString("name: x\nlength_m: 1\nwidth_m: 1\n[a, b]: 1\n"),
               ConfigError);
}

TEST(RobotProfileTest, YamlRoundTripAndHash) {
  const RobotProfile p = LoadRobotProfileString(kPioneer);
  const RobotProfile q = LoadRobotProfileString(p.ToYaml());
  EXPECT_EQ(p, q);
  EXPECT_EQ(p.ContentHash(), q.ContentHash());
  RobotProfile r = p;
  r.max_slope_up_rad = 9.0 * M_PI / 180.0;
  EXPECT_NE(r.ContentHash(), p.ContentHash());
  EXPECT_EQ(p.ContentHash().size(), 16u);
}

TEST(RobotProfileTest, ShippedProfilesLoad) {
  for (const char* name :
       {"pioneer3at", "kobuki", "p3dx", "robauco", "sparus2_msis", "girona500", "rover"}) {
    const std::string path = std::string(CAIRN_SOURCE_DIR) + "/config/profiles/" + name + ".yaml";
    SCOPED_TRACE(path);
    const RobotProfile p = LoadRobotProfileFile(path);
    EXPECT_EQ(p.name, name);
  }
  const RobotProfile p3at =
      LoadRobotProfileFile(std::string(CAIRN_SOURCE_DIR) + "/config/profiles/pioneer3at.yaml");
  EXPECT_NEAR(p3at.max_slope_up_rad * 180.0 / M_PI, 8.0, 1e-9);
  EXPECT_DOUBLE_EQ(p3at.max_step_up_m, 0.03);
  EXPECT_DOUBLE_EQ(p3at.max_step_down_m, 0.10);
}

}  // namespace
}  // namespace cairn::common
