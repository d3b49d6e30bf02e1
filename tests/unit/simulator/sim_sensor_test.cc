// The sensor seam: a tiny sensor written here, outside the simulator, registered by name
// through the public registry, loaded from YAML and built by MujocoSim like any other.
#include "simulator/sim_sensor.h"

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "common/check.h"
#include "simulator/mujoco_sim.h"
#include "simulator/sensor_registry.h"
#include "simulator/sensors/planar_laser_sensor.h"
#include "tests/unit/simulator/sim_test_util.h"

namespace cairn::sim {
namespace {

using testing::FlatWorld;
using testing::InlineScenario;
using testing::SimTest;

// A one-beam rangefinder looking along its site's x axis.
struct RangefinderParams {
  double rate_hz{20.0};
  std::string site{"laser_mount"};

  void Validate() const { CAIRN_THROW_UNLESS(rate_hz > 0.0, "rangefinder.rate_hz must be > 0"); }
};

RangefinderParams LoadRangefinderParams(common::YamlMap& map, const RangefinderParams& defaults) {
  RangefinderParams p = defaults;
  map.Get("rate_hz", &p.rate_hz);
  map.Get("site", &p.site);
  FinishSensorParams(map, p);
  return p;
}

struct RangefinderReading {
  int64_t utime{0};
  std::string robot;
  double sensor_x_m{0.0};
  double range_m{-1.0};
};

class RangefinderSensor final : public SimSensor {
 public:
  static constexpr char kName[] = "rangefinder";
  static constexpr char kDescription[] = "one beam straight ahead (a test sensor)";
  using Params = RangefinderParams;
  using Reading = RangefinderReading;
  static constexpr auto kLoadParams = &LoadRangefinderParams;

  RangefinderSensor(const RangefinderParams& params, const SensorContext& context)
      : robot_(context.robot), site_(context.RequireSite(params.site)), hits_(1) {
    schedule_.rate_hz = params.rate_hz;
    pattern_.directions = {Eigen::Vector3d::UnitX()};
    pattern_.BuildGroups(1);
  }

  bool Due(double now_s) const override { return schedule_.Due(now_s); }
  bool CastsRays() const override { return true; }
  void Produce(const SensorFrame& frame, SimOutputs* out) override {
    schedule_.Advance(frame.now_s);
    const common::Pose3 pose = SitePose(frame.data, site_);
    frame.CastAll(pose, pattern_, 30.0, &hits_);
    out->Add(kName, RangefinderReading{frame.utime, robot_, pose.position_m.x(), hits_[0].range_m});
  }

 private:
  std::string robot_;
  int site_;
  SensorSchedule schedule_;
  RayPattern pattern_;
  std::vector<RayHit> hits_;
};

SensorRegistry RegistryWithRangefinder() {
  SensorRegistry registry = BuiltinSensors();
  registry.Add(KindOf<RangefinderSensor>());
  return registry;
}

// A wall whose face is at x = 3.
std::string WallWorld() { return FlatWorld(R"(<geom type="box" size="0.1 3 1" pos="3.1 0 1"/>)"); }

class SimSensorSeamTest : public SimTest {};

TEST_F(SimSensorSeamTest, ASensorRegisteredByNameIsLoadedBuiltAndProduces) {
  const SensorRegistry registry = RegistryWithRangefinder();
  common::YamlMap map = common::YamlMap::FromString(
      "rangefinder: {rate_hz: 5.0}\nplanar_laser: {range_noise_sigma_m: 0.0}\n", "inline.yaml");
  Scenario s = InlineScenario(WallWorld(), "r", "p3dx");
  s.robots[0].sensors = LoadSensorSet(map, s.robots[0].model.default_sensors, registry);
  // The registry's order, whatever the file's.
  EXPECT_EQ(s.robots[0].sensors.Names(), (std::vector<std::string>{"planar_laser", "rangefinder"}));
  MujocoSim sim(s);
  SimOutputs out;
  while (sim.time_s() < 1.0 - 1e-9) sim.Step(&out);

  const auto& readings = out.Readings<RangefinderSensor>();
  ASSERT_EQ(readings.size(), 5u);
  EXPECT_EQ(readings.front().utime, 200000);
  EXPECT_EQ(readings.back().utime, 1000000);
  EXPECT_EQ(readings.back().robot, "r");
  // Its ray went through the simulator's caster: the wall's face, as the planar laser's
  // centre beam (same site, no noise) sees it.
  EXPECT_NEAR(readings.back().sensor_x_m + readings.back().range_m, 3.0, 1e-5);
  const common::LaserScan& scan = out.Readings<PlanarLaserSensor>().back();
  const size_t centre = scan.ranges_m.size() / 2;
  EXPECT_FLOAT_EQ(scan.ranges_m[centre], static_cast<float>(readings.back().range_m));
  // The simulator hands the built sensor back by class.
  EXPECT_NE(sim.FindSensor<RangefinderSensor>("r"), nullptr);
}

TEST_F(SimSensorSeamTest, ASensorSetInCodeNeedsNoRegistry) {
  Scenario s = InlineScenario(WallWorld(), "r", "p3dx");
  s.robots[0].sensors = SensorSet{};
  s.robots[0].sensors.Set<RangefinderSensor>().rate_hz = 10.0;
  MujocoSim sim(s);
  SimOutputs out;
  while (sim.time_s() < 0.5 - 1e-9) sim.Step(&out);
  EXPECT_EQ(out.Readings<RangefinderSensor>().size(), 5u);
  EXPECT_EQ(sim.FindSensor<PlanarLaserSensor>("r"), nullptr);
  // A sensor that does not override Trigger has no on-request mode: the default refuses, and
  // the simulator names the robot and the kind.
  const common::Status trigger = sim.TriggerSensor("r", "rangefinder");
  EXPECT_EQ(trigger.code(), common::StatusCode::kInvalidArgument);
  EXPECT_EQ(trigger.message(), "robot 'r', sensor 'rangefinder': no on-request mode");
}

TEST_F(SimSensorSeamTest, ItsMistakesAreReportedLikeAnyOther) {
  const SensorRegistry registry = RegistryWithRangefinder();
  // A bad value names the file and line.
  common::YamlMap bad = common::YamlMap::FromString("rangefinder:\n  rate_hz: -1\n", "inline.yaml");
  try {
    LoadSensorSet(bad, SensorSet{}, registry);
    FAIL() << "no error";
  } catch (const common::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("inline.yaml:2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("rangefinder.rate_hz must be > 0"), std::string::npos);
  }
  // A missing site names the robot, the sensor and the site.
  Scenario s = InlineScenario(WallWorld(), "r", "p3dx");
  s.robots[0].sensors.Set<RangefinderSensor>().site = "nowhere";
  try {
    MujocoSim sim(s);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sensor 'rangefinder' needs a site named 'nowhere'"),
              std::string::npos)
        << e.what();
  }
}

TEST(SensorScheduleTest, ReadingsFallDueAtMultiplesOfThePeriodWithoutBursts) {
  SensorSchedule schedule;
  schedule.rate_hz = 50.0;
  EXPECT_FALSE(schedule.Due(0.0));
  EXPECT_FALSE(schedule.Due(0.0199));
  EXPECT_TRUE(schedule.Due(0.02));
  schedule.Advance(0.02);
  EXPECT_EQ(schedule.count, 1);
  EXPECT_FALSE(schedule.Due(0.039));
  // A long gap counts every reading it missed once: the next falls due after it.
  schedule.Advance(0.1);
  EXPECT_EQ(schedule.count, 5);
  EXPECT_FALSE(schedule.Due(0.1));
  // Integer counts: after 10^6 readings the period has not drifted.
  schedule.count = 1000000;
  EXPECT_TRUE(schedule.Due(20000.02));
  EXPECT_FALSE(schedule.Due(20000.0199));
}

TEST(SensorScheduleTest, SkipToPassesEveryReadingDueWithoutProducingThem) {
  SensorSchedule schedule;
  schedule.rate_hz = 50.0;
  schedule.SkipTo(0.0);
  EXPECT_EQ(schedule.count, 0);
  schedule.SkipTo(0.05);  // readings 1 and 2 (0.02, 0.04) passed; the next at 0.06
  EXPECT_EQ(schedule.count, 2);
  EXPECT_FALSE(schedule.Due(0.0599));
  EXPECT_TRUE(schedule.Due(0.06));
  // On a reading time that reading counts as passed: the next is one period later.
  schedule.SkipTo(0.1);
  EXPECT_EQ(schedule.count, 5);
  EXPECT_FALSE(schedule.Due(0.1));
  // The same count as Advance after a long idle time, however large; never backwards.
  SensorSchedule advanced = schedule;
  advanced.Advance(3600.02);
  schedule.SkipTo(3600.02);
  EXPECT_EQ(schedule.count, advanced.count);
  EXPECT_EQ(schedule.count, 180001);
  schedule.SkipTo(1.0);
  EXPECT_EQ(schedule.count, 180001);
  // Rates whose periods are not exact in binary agree with Due too.
  for (double rate : {3.0, 7.0, 1250.0, 0.3}) {
    for (double t : {0.1, 1.0 / 3.0, 2.0 / 7.0, 10.0 / 3.0, 12.345}) {
      SensorSchedule a, b;
      a.rate_hz = b.rate_hz = rate;
      a.Advance(t);
      b.SkipTo(t);
      EXPECT_EQ(a.count, b.count) << rate << " " << t;
    }
  }
}

}  // namespace
}  // namespace cairn::sim
