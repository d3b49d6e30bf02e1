#include "simulator/scenario.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "common/check.h"
#include "simulator/mujoco_model.h"

#ifndef CAIRN_SIM_DATA_DIR
#define CAIRN_SIM_DATA_DIR "simulator"
#endif
#ifndef CAIRN_CONFIG_DIR
#define CAIRN_CONFIG_DIR "config"
#endif

namespace cairn::sim {
namespace fs = std::filesystem;
namespace {

std::vector<std::string> NamesWithExtension(const std::string& dir, const std::string& ext) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (entry.path().extension() == ext) names.push_back(entry.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

bool LooksLikePath(const std::string& s) {
  return s.find('/') != std::string::npos || s.find('.') != std::string::npos;
}

// Reads an angle given as <key>_rad or <key>_deg (at most one of them).
bool GetAngle(common::YamlMap& map, const std::string& key, double* out_rad) {
  const bool has_rad = map.Has(key + "_rad");
  const bool has_deg = map.Has(key + "_deg");
  if (has_rad && has_deg)
    map.Fail(map.Raw(key + "_deg"), "give " + key + " in _rad or _deg, not both");
  if (has_rad) return map.Get(key + "_rad", out_rad);
  double deg = 0.0;
  if (has_deg && map.Get(key + "_deg", &deg)) {
    *out_rad = deg * M_PI / 180.0;
    return true;
  }
  return false;
}

std::vector<std::string> GetStringList(common::YamlMap& map, const std::string& key) {
  std::vector<std::string> out;
  if (!map.Has(key)) return out;
  YAML::Node node = map.Raw(key);
  if (!node.IsSequence()) map.Fail(node, "'" + key + "' must be a list of names");
  for (const auto& item : node) out.push_back(item.as<std::string>());
  return out;
}

// Runs a Validate() and reports its message at the map's location.
template <typename Fn>
void ValidateAt(common::YamlMap& map, Fn&& fn) {
  try {
    fn();
  } catch (const std::invalid_argument& e) {
    throw common::ConfigError(map.Where() + e.what());
  }
}

}  // namespace

// --- paths -------------------------------------------------------------------------------------

SimPaths SimPaths::Default() {
  SimPaths p;
  const char* data = std::getenv("CAIRN_SIM_DATA_DIR");
  const char* config = std::getenv("CAIRN_CONFIG_DIR");
  p.data_dir = data && *data ? data : CAIRN_SIM_DATA_DIR;
  p.config_dir = config && *config ? config : CAIRN_CONFIG_DIR;
  return p;
}

std::vector<std::string> SimPaths::ShippedWorlds() const {
  return NamesWithExtension(data_dir + "/worlds", ".xml");
}

std::vector<std::string> SimPaths::ShippedRobots() const {
  return NamesWithExtension(data_dir + "/robots", ".yaml");
}

std::string SimPaths::WorldPath(const std::string& name_or_path) const {
  if (LooksLikePath(name_or_path)) return name_or_path;
  const std::string path = data_dir + "/worlds/" + name_or_path + ".xml";
  if (!fs::exists(path)) {
    throw std::invalid_argument("unknown world '" + name_or_path + "' (shipped worlds: " +
                                Join(ShippedWorlds()) + "; or give an MJCF file path)");
  }
  return path;
}

std::string SimPaths::ProfilePath(const std::string& name_or_path) const {
  if (LooksLikePath(name_or_path)) return name_or_path;
  const std::string path = config_dir + "/profiles/" + name_or_path + ".yaml";
  if (!fs::exists(path)) {
    throw std::invalid_argument("unknown profile '" + name_or_path + "' (known profiles: " +
                                Join(NamesWithExtension(config_dir + "/profiles", ".yaml")) +
                                "; or give a profile file path)");
  }
  return path;
}

std::string SimPaths::WorldSummary(const std::string& name) const {
  // The first comment of a world file is its summary.
  std::ifstream in(data_dir + "/worlds/" + name + ".xml");
  std::string line;
  while (std::getline(in, line)) {
    const size_t open = line.find("<!--");
    if (open == std::string::npos) continue;
    std::string text = line.substr(open + 4);
    const size_t close = text.find("-->");
    if (close != std::string::npos) text = text.substr(0, close);
    while (!text.empty() && text.front() == ' ') text.erase(text.begin());
    while (!text.empty() && text.back() == ' ') text.pop_back();
    if (text.rfind(name + ":", 0) == 0) text = text.substr(name.size() + 1);
    while (!text.empty() && text.front() == ' ') text.erase(text.begin());
    return text;
  }
  return "";
}

// --- sensors -----------------------------------------------------------------------------------

void LoadLidarParams(common::YamlMap& map, LidarParams* p) {
  map.Get("rings", &p->rings);
  map.Get("min_elevation_deg", &p->min_elevation_deg);
  map.Get("max_elevation_deg", &p->max_elevation_deg);
  map.Get("azimuth_steps", &p->azimuth_steps);
  map.Get("rate_hz", &p->rate_hz);
  map.Get("slices_per_revolution", &p->slices_per_revolution);
  map.Get("max_range_m", &p->max_range_m);
  map.Get("min_range_m", &p->min_range_m);
  map.Get("range_noise_sigma_m", &p->range_noise_sigma_m);
  map.Get("azimuths_per_ray_group", &p->azimuths_per_ray_group);
  map.Get("rings_per_ray_group", &p->rings_per_ray_group);
  map.Get("mount_site", &p->mount_site);
  map.Finish();
  ValidateAt(map, [&] { p->Validate(); });
}

void LoadPlanarLaserParams(common::YamlMap& map, PlanarLaserParams* p) {
  map.Get("fov_deg", &p->fov_deg);
  map.Get("beams", &p->beams);
  map.Get("max_range_m", &p->max_range_m);
  map.Get("min_range_m", &p->min_range_m);
  map.Get("rate_hz", &p->rate_hz);
  map.Get("range_noise_sigma_m", &p->range_noise_sigma_m);
  map.Get("mount_site", &p->mount_site);
  map.Finish();
  ValidateAt(map, [&] { p->Validate(); });
}

void LoadTurretParams(common::YamlMap& map, TurretParams* p) {
  map.Get("fan_fov_deg", &p->fan_fov_deg);
  map.Get("fan_beams", &p->fan_beams);
  map.Get("max_range_m", &p->max_range_m);
  map.Get("min_range_m", &p->min_range_m);
  map.Get("line_rate_hz", &p->line_rate_hz);
  map.Get("pan_step_deg", &p->pan_step_deg);
  map.Get("pan_range_deg", &p->pan_range_deg);
  map.Get("range_noise_sigma_m", &p->range_noise_sigma_m);
  map.Get("mount_site", &p->mount_site);
  map.Finish();
  ValidateAt(map, [&] { p->Validate(); });
}

void LoadOdometryParams(common::YamlMap& map, OdometryParams* p) {
  map.Get("rate_hz", &p->rate_hz);
  map.Get("slip_noise_ratio", &p->slip_noise_ratio);
  map.Finish();
  ValidateAt(map, [&] { p->Validate(); });
}

void LoadImuParams(common::YamlMap& map, ImuParams* p) {
  map.Get("rate_hz", &p->rate_hz);
  map.Get("gyro_noise_sigma_radps", &p->gyro_noise_sigma_radps);
  map.Get("accel_noise_sigma_mps2", &p->accel_noise_sigma_mps2);
  map.Get("orientation_noise_sigma_rad", &p->orientation_noise_sigma_rad);
  map.Get("site", &p->site);
  map.Finish();
  ValidateAt(map, [&] { p->Validate(); });
}

void LoadGroundTruthParams(common::YamlMap& map, GroundTruthParams* p) {
  map.Get("rate_hz", &p->rate_hz);
  map.Finish();
  ValidateAt(map, [&] { p->Validate(); });
}

SensorSet LoadSensorSet(common::YamlMap& map, const SensorSet& defaults) {
  SensorSet set;
  for (const std::string& name : map.Keys()) {
    common::YamlMap child = map.Child(name);
    if (name == kSensorLidar) {
      set.lidar = defaults.lidar.value_or(LidarParams{});
      LoadLidarParams(child, &*set.lidar);
    } else if (name == kSensorPlanarLaser) {
      set.planar_laser = defaults.planar_laser.value_or(PlanarLaserParams{});
      LoadPlanarLaserParams(child, &*set.planar_laser);
    } else if (name == kSensorTurret) {
      set.turret = defaults.turret.value_or(TurretParams{});
      LoadTurretParams(child, &*set.turret);
    } else if (name == kSensorOdometry) {
      set.odometry = defaults.odometry.value_or(OdometryParams{});
      LoadOdometryParams(child, &*set.odometry);
    } else if (name == kSensorImu) {
      set.imu = defaults.imu.value_or(ImuParams{});
      LoadImuParams(child, &*set.imu);
    } else if (name == kSensorGroundTruth) {
      set.ground_truth = defaults.ground_truth.value_or(GroundTruthParams{});
      LoadGroundTruthParams(child, &*set.ground_truth);
    } else {
      std::string known;
      for (const auto& [n, d] : SensorCatalogue()) known += (known.empty() ? "" : ", ") + n;
      map.Fail(map.Raw(name), "unknown sensor '" + name + "' (known: " + known + ")");
    }
  }
  return set;
}

// --- robot models ------------------------------------------------------------------------------

RobotModel LoadRobotModel(const SimPaths& paths, const std::string& model) {
  const std::string yaml_path = paths.data_dir + "/robots/" + model + ".yaml";
  const std::string xml_path = paths.data_dir + "/robots/" + model + ".xml";
  if (model.empty() || LooksLikePath(model) || !fs::exists(yaml_path) || !fs::exists(xml_path)) {
    throw std::invalid_argument("unknown robot model '" + model +
                                "' (known models: " + Join(paths.ShippedRobots()) + ")");
  }
  RobotModel m;
  m.name = model;
  m.xml_path = xml_path;
  m.xml = ReadTextFile(xml_path);
  common::YamlMap map = common::YamlMap::LoadFile(yaml_path);
  m.description = map.Require<std::string>("description");
  const std::string drive = map.Require<std::string>("drive");
  try {
    m.drive = common::DriveKindFromName(drive);
  } catch (const std::invalid_argument& e) {
    map.Fail(map.Raw("drive"), e.what());
  }
  m.wheel_radius_m = map.Require<double>("wheel_radius_m");
  m.track_m = map.Require<double>("track_m");
  m.left_wheels = GetStringList(map, "left_wheels");
  m.right_wheels = GetStringList(map, "right_wheels");
  m.default_profile = map.Require<std::string>("default_profile");
  common::YamlMap sensors = map.Child("sensors");
  m.default_sensors = LoadSensorSet(sensors, SensorSet{});
  map.Finish();
  if (!(m.wheel_radius_m > 0.0) || !(m.track_m > 0.0) || m.left_wheels.empty() ||
      m.right_wheels.empty()) {
    throw common::ConfigError(yaml_path +
                              ": needs wheel_radius_m > 0, track_m > 0 and left/right wheels");
  }
  return m;
}

// --- robots and scenarios ----------------------------------------------------------------------

RobotSpec MakeRobotSpec(const std::string& id, const std::string& model, const std::string& profile,
                        const SpawnPose& spawn, const SimPaths& paths) {
  RobotSpec spec;
  spec.id = id;
  spec.model = LoadRobotModel(paths, model);
  const std::string profile_name = profile.empty() ? spec.model.default_profile : profile;
  spec.profile = common::LoadRobotProfileFile(paths.ProfilePath(profile_name));
  spec.spawn = spawn;
  spec.sensors = spec.model.default_sensors;
  return spec;
}

RobotSpec ParseRobotFlag(const std::string& text, const SimPaths& paths) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, ':');) parts.push_back(part);
  if (parts.size() < 2 || parts.size() > 4 || parts[0].empty() || parts[1].empty()) {
    throw std::invalid_argument("--robot '" + text +
                                "': expected id:model[:profile[:x,y[,yaw_deg]]]");
  }
  SpawnPose spawn;
  if (parts.size() == 4) {
    std::vector<double> values;
    std::stringstream pose(parts[3]);
    for (std::string v; std::getline(pose, v, ',');) {
      char* end = nullptr;
      const double d = std::strtod(v.c_str(), &end);
      if (v.empty() || *end != '\0' || !std::isfinite(d)) {
        throw std::invalid_argument("--robot '" + text + "': bad number '" + v + "' in the pose");
      }
      values.push_back(d);
    }
    if (values.size() < 2 || values.size() > 3) {
      throw std::invalid_argument("--robot '" + text + "': the pose is x,y or x,y,yaw_deg");
    }
    spawn.x_m = values[0];
    spawn.y_m = values[1];
    if (values.size() == 3) spawn.yaw_rad = values[2] * M_PI / 180.0;
  }
  return MakeRobotSpec(parts[0], parts[1], parts.size() >= 3 ? parts[2] : "", spawn, paths);
}

void PhysicsParams::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(timestep_s) && timestep_s > 0.0 && timestep_s <= 0.05,
                     "physics.timestep_s must be in (0, 0.05]");
  CAIRN_THROW_UNLESS(integrator == "euler" || integrator == "rk4" || integrator == "implicit",
                     "physics.integrator must be euler, rk4 or implicit (MuJoCo 2.2)");
}

void Scenario::Validate() const {
  physics.Validate();
  CAIRN_THROW_UNLESS(ray_threads >= 1 && ray_threads <= 64, "ray_threads must be in [1, 64]");
  CAIRN_THROW_UNLESS(spawn_slots >= 0 && spawn_slots <= 256, "spawn_slots must be in [0, 256]");
  CAIRN_THROW_UNLESS(std::isfinite(clock_rate_hz) && clock_rate_hz > 0.0,
                     "clock_rate_hz must be > 0");
  std::set<std::string> ids;
  for (const RobotSpec& r : robots) {
    CAIRN_THROW_UNLESS(ids.insert(r.id).second, "robot id '" << r.id << "' appears twice");
    CAIRN_THROW_UNLESS(std::isfinite(r.spawn.x_m) && std::isfinite(r.spawn.y_m) &&
                           std::isfinite(r.spawn.yaw_rad) &&
                           (!r.spawn.z_m || std::isfinite(*r.spawn.z_m)),
                       "robot '" << r.id << "': spawn pose must be finite");
    r.sensors.Validate();
    for (const ScriptedCommand& c : r.commands) {
      CAIRN_THROW_UNLESS(std::isfinite(c.at_s) && std::isfinite(c.duration_s) &&
                             std::isfinite(c.linear_mps) && std::isfinite(c.angular_radps) &&
                             c.duration_s >= 0.0,
                         "robot '" << r.id << "': scripted commands must be finite");
    }
  }
}

Scenario LoadScenario(common::YamlMap& map, const SimPaths& paths) {
  Scenario s;
  s.world = map.Require<std::string>("world");
  try {
    std::string path = s.world;
    // A relative file path is taken relative to the scenario file first.
    if (LooksLikePath(path) && !fs::path(path).is_absolute()) {
      const fs::path beside = fs::path(map.file()).parent_path() / path;
      if (fs::exists(beside)) path = beside.string();
    }
    s.world_path = paths.WorldPath(path);
  } catch (const std::invalid_argument& e) {
    map.Fail(map.Raw("world"), e.what());
  }
  int64_t seed = 1;
  if (map.Get("seed", &seed) && seed < 0) map.Fail(map.Raw("seed"), "seed must be >= 0");
  s.seed = static_cast<uint64_t>(seed);
  {
    common::YamlMap physics = map.Child("physics");
    physics.Get("timestep_s", &s.physics.timestep_s);
    physics.Get("integrator", &s.physics.integrator);
    physics.Finish();
  }
  map.Get("ray_threads", &s.ray_threads);
  map.Get("spawn_slots", &s.spawn_slots);
  map.Get("clock_rate_hz", &s.clock_rate_hz);

  YAML::Node robots = map.Raw("robots");
  if (robots && !robots.IsSequence()) map.Fail(robots, "'robots' must be a list");
  int index = 0;
  for (const auto& node : robots) {
    common::YamlMap r = map.Wrap(node, "robots[" + std::to_string(index++) + "]");
    const std::string id = r.Require<std::string>("id");
    const std::string model = r.Require<std::string>("model");
    std::string profile;
    r.Get("profile", &profile);
    SpawnPose spawn;
    {
      common::YamlMap sp = r.Child("spawn");
      sp.Get("x_m", &spawn.x_m);
      sp.Get("y_m", &spawn.y_m);
      GetAngle(sp, "yaw", &spawn.yaw_rad);
      double z = 0.0;
      if (sp.Get("z_m", &z)) spawn.z_m = z;
      sp.Finish();
    }
    RobotSpec spec;
    try {
      spec = MakeRobotSpec(id, model, profile, spawn, paths);
    } catch (const std::invalid_argument& e) {
      r.Fail(node, e.what());
    }
    if (r.Has("sensors")) {
      common::YamlMap sensors = r.Child("sensors");
      spec.sensors = LoadSensorSet(sensors, spec.model.default_sensors);
    }
    if (r.Has("commands")) {
      YAML::Node list = r.Raw("commands");
      if (!list.IsSequence()) r.Fail(list, "'commands' must be a list");
      for (const auto& item : list) {
        common::YamlMap c = r.Wrap(item, "commands");
        ScriptedCommand cmd;
        cmd.at_s = c.Require<double>("at_s");
        cmd.duration_s = c.Require<double>("duration_s");
        c.Get("linear_mps", &cmd.linear_mps);
        c.Get("angular_radps", &cmd.angular_radps);
        c.Finish();
        spec.commands.push_back(cmd);
      }
    }
    r.Finish();
    s.robots.push_back(std::move(spec));
  }
  map.Finish();
  ValidateAt(map, [&] { s.Validate(); });
  return s;
}

Scenario LoadScenarioFile(const std::string& path, const SimPaths& paths) {
  common::YamlMap map = common::YamlMap::LoadFile(path);
  return LoadScenario(map, paths);
}

}  // namespace cairn::sim
