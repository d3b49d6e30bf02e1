#include "simulator/sensor_registry.h"

#include <string>

#include <gtest/gtest.h>

#include "simulator/catalogue.h"
#include "simulator/sensors/ground_truth_sensor.h"
#include "simulator/sensors/imu_sensor.h"
#include "simulator/sensors/lidar_sensor.h"
#include "simulator/sensors/odometry_sensor.h"
#include "simulator/sensors/planar_laser_sensor.h"
#include "simulator/sensors/turret_sensor.h"

namespace cairn::sim {
namespace {

// The message of the ConfigError `fn` throws ("" when it throws none).
template <typename Fn>
std::string ConfigErrorOf(Fn&& fn) {
  try {
    fn();
  } catch (const common::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(SensorRegistryTest, BuiltinsInCatalogueOrderEachWithADescription) {
  // The first six, in this order; sensors added later follow them.
  const std::vector<std::string> first = {"hdl32e",   "planar_laser", "turret",
                                          "odometry", "imu",          "ground_truth"};
  const auto catalogue = BuiltinSensors().Catalogue();
  ASSERT_GE(catalogue.size(), first.size());
  for (size_t i = 0; i < first.size(); ++i) {
    EXPECT_EQ(catalogue[i].first, first[i]);
    EXPECT_EQ(BuiltinSensors().IndexOf(first[i]), i);
  }
  EXPECT_EQ(BuiltinSensors().Find("flux_capacitor"), nullptr);
  EXPECT_EQ(BuiltinSensors().IndexOf("flux_capacitor"), catalogue.size());
  // Every one has a description, and --help lists it.
  const std::string help = DescribeSensors();
  for (const auto& [name, description] : catalogue) {
    EXPECT_FALSE(description.empty()) << name;
    EXPECT_NE(help.find("  " + name + ": " + description + "\n"), std::string::npos) << name;
  }
}

TEST(SensorRegistryTest, ANameIsRegisteredOnce) {
  SensorRegistry registry = BuiltinSensors();
  EXPECT_THROW(registry.Add(KindOf<ImuSensor>()), std::invalid_argument);
}

TEST(SensorSetTest, SetFindRemoveAndValidate) {
  SensorSet set;
  EXPECT_EQ(set.Find<ImuSensor>(), nullptr);
  set.Set<ImuSensor>().rate_hz = 200.0;
  set.Set<LidarSensor>();
  EXPECT_TRUE(set.Has("imu"));
  EXPECT_EQ(set.Find<ImuSensor>()->rate_hz, 200.0);
  EXPECT_EQ(set.Names(), (std::vector<std::string>{"imu", "hdl32e"}));
  set.Set<ImuSensor>(ImuParams{});  // replaced in place
  EXPECT_EQ(set.Find<ImuSensor>()->rate_hz, 100.0);
  EXPECT_EQ(set.Names(), (std::vector<std::string>{"imu", "hdl32e"}));
  EXPECT_NO_THROW(set.Validate());
  set.Find<LidarSensor>()->rings = 0;
  EXPECT_THROW(set.Validate(), std::invalid_argument);
  set.Remove("hdl32e");
  EXPECT_FALSE(set.Has("hdl32e"));
  EXPECT_NO_THROW(set.Validate());
  // Copies are independent.
  SensorSet copy = set;
  copy.Find<ImuSensor>()->rate_hz = 5.0;
  EXPECT_EQ(set.Find<ImuSensor>()->rate_hz, 100.0);
}

TEST(LoadSensorSetTest, ListedSensorsOnlyInRegistryOrderFromTheModelsDefaults) {
  SensorSet defaults;
  defaults.Set<PlanarLaserSensor>().fov_deg = 270.0;
  defaults.Set<OdometrySensor>();
  common::YamlMap map = common::YamlMap::FromString(
      "ground_truth: {}\nplanar_laser: {rate_hz: 20}\nturret: {pan_step_deg: 1.0}\n"
      "imu: {site: imu2}\n",
      "inline.yaml");
  const SensorSet set = LoadSensorSet(map, defaults);
  EXPECT_EQ(set.Names(),
            (std::vector<std::string>{"planar_laser", "turret", "imu", "ground_truth"}));
  EXPECT_EQ(set.Find<PlanarLaserSensor>()->fov_deg, 270.0);  // the default survives
  EXPECT_EQ(set.Find<PlanarLaserSensor>()->rate_hz, 20.0);
  EXPECT_EQ(set.Find<TurretSensor>()->pan_step_deg, 1.0);
  EXPECT_EQ(set.Find<TurretSensor>()->fan_beams, 541);  // no default in the set: the struct's
  EXPECT_EQ(set.Find<ImuSensor>()->site, "imu2");
  EXPECT_FALSE(set.Has("odometry"));  // not listed: off
}

TEST(LoadSensorSetTest, MistakesNameTheFileAndLine) {
  auto load = [](const std::string& text) {
    return ConfigErrorOf([&] {
      common::YamlMap map = common::YamlMap::FromString(text, "robot.yaml");
      LoadSensorSet(map, SensorSet{});
    });
  };
  const std::string unknown = load("imu: {}\nflux_capacitor: {}\n");
  EXPECT_NE(unknown.find("robot.yaml:2"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("unknown sensor 'flux_capacitor' (known: hdl32e, planar_laser, turret, "
                         "odometry, imu, ground_truth"),
            std::string::npos)
      << unknown;
  const std::string key = load("imu: {}\nhdl32e:\n  rings: 16\n  ringz: 3\n");
  EXPECT_NE(key.find("robot.yaml:4"), std::string::npos) << key;
  EXPECT_NE(key.find("ringz"), std::string::npos) << key;
  const std::string value = load("odometry:\n  slip_noise_ratio: 1.5\n");
  EXPECT_NE(value.find("robot.yaml:2"), std::string::npos) << value;
  EXPECT_NE(value.find("odometry.slip_noise_ratio must be in [0, 1)"), std::string::npos) << value;
  EXPECT_NE(load("planar_laser: {beams: many}\n").find("robot.yaml:1"), std::string::npos);
}

}  // namespace
}  // namespace cairn::sim
