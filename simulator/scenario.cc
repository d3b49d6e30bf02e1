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
  for (const auto& item : node) out.push_back(map.As<std::string>(item, "a name"));
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

SimPaths SimPaths::InTree(const std::string& root) {
  SimPaths p;
  p.data_dir = root + "/simulator";
  p.config_dir = root + "/config";
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
  if (m.drive == common::DriveKind::kAuv) {
    // No wheels: thrusters, and a unicycle track for the odometry's wheel motion.
    m.wheel_radius_m = 1.0;
    m.track_m = 1.0;
    map.Get("track_m", &m.track_m);
    map.Get("max_surge_thrust_n", &m.thrusters.max_surge_thrust_n);
    map.Get("max_yaw_torque_nm", &m.thrusters.max_yaw_torque_nm);
    map.Get("max_heave_thrust_n", &m.thrusters.max_heave_thrust_n);
    map.Get("buoyancy_centre_m", &m.thrusters.buoyancy_centre_m);
  } else {
    m.wheel_radius_m = map.Require<double>("wheel_radius_m");
    m.track_m = map.Require<double>("track_m");
    m.left_wheels = GetStringList(map, "left_wheels");
    m.right_wheels = GetStringList(map, "right_wheels");
  }
  m.default_profile = map.Require<std::string>("default_profile");
  common::YamlMap sensors = map.Child("sensors");
  m.default_sensors = LoadSensorSet(sensors, SensorSet{});
  map.Finish();
  if (m.drive == common::DriveKind::kAuv) {
    const RobotModel::Thrusters& t = m.thrusters;
    if (!(m.track_m > 0.0) || !(t.max_surge_thrust_n > 0.0) || !(t.max_yaw_torque_nm > 0.0) ||
        !(t.max_heave_thrust_n > 0.0) || !std::isfinite(t.max_surge_thrust_n) ||
        !std::isfinite(t.max_yaw_torque_nm) || !std::isfinite(t.max_heave_thrust_n) ||
        !(std::abs(t.buoyancy_centre_m) <= 1.0)) {
      throw common::ConfigError(yaml_path +
                                ": an auv needs track_m, max_surge_thrust_n, max_yaw_torque_nm "
                                "and max_heave_thrust_n > 0 and |buoyancy_centre_m| <= 1");
    }
  } else if (!(m.wheel_radius_m > 0.0) || !(m.track_m > 0.0) || m.left_wheels.empty() ||
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

Scenario MakeScenario(const std::string& world, const std::vector<std::string>& robot_flags,
                      const SimPaths& paths) {
  Scenario s;
  s.world = world;
  s.world_path = paths.WorldPath(world);
  for (const std::string& flag : robot_flags) s.robots.push_back(ParseRobotFlag(flag, paths));
  return s;
}

void PhysicsParams::Validate() const {
  CAIRN_THROW_UNLESS(std::isfinite(timestep_s) && timestep_s > 0.0 && timestep_s <= 0.05,
                     "physics.timestep_s must be in (0, 0.05]");
  CAIRN_THROW_UNLESS(integrator == "euler" || integrator == "rk4" || integrator == "implicit",
                     "physics.integrator must be euler, rk4 or implicit (MuJoCo 2.2)");
  CAIRN_THROW_UNLESS(std::isfinite(current_x_mps) && std::isfinite(current_y_mps) &&
                         std::hypot(current_x_mps, current_y_mps) <= 5.0,
                     "physics.current_x_mps and current_y_mps must be finite, at most 5 m/s");
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

PhysicsParams LoadPhysicsParams(common::YamlMap& map) {
  PhysicsParams p;
  map.Get("timestep_s", &p.timestep_s);
  map.Get("integrator", &p.integrator);
  map.Get("current_x_mps", &p.current_x_mps);
  map.Get("current_y_mps", &p.current_y_mps);
  map.Finish();
  return p;
}

namespace {

// The scenario's world: a shipped name or an MJCF path, a relative one taken relative to the
// scenario file first.
std::string ResolveWorld(common::YamlMap& map, const std::string& world, const SimPaths& paths) {
  try {
    std::string path = world;
    if (LooksLikePath(path) && !fs::path(path).is_absolute()) {
      const fs::path beside = fs::path(map.file()).parent_path() / path;
      if (fs::exists(beside)) path = beside.string();
    }
    return paths.WorldPath(path);
  } catch (const std::invalid_argument& e) {
    map.Fail(map.Raw("world"), e.what());
  }
}

SpawnPose LoadSpawn(common::YamlMap& map) {
  SpawnPose spawn;
  map.Get("x_m", &spawn.x_m);
  map.Get("y_m", &spawn.y_m);
  GetAngle(map, "yaw", &spawn.yaw_rad);
  double z = 0.0;
  if (map.Get("z_m", &z)) spawn.z_m = z;
  map.Finish();
  return spawn;
}

std::vector<ScriptedCommand> LoadCommands(common::YamlMap& robot) {
  std::vector<ScriptedCommand> commands;
  YAML::Node list = robot.Raw("commands");
  if (!list.IsSequence()) robot.Fail(list, "'commands' must be a list");
  for (const auto& item : list) {
    common::YamlMap c = robot.Wrap(item, "commands");
    ScriptedCommand cmd;
    cmd.at_s = c.Require<double>("at_s");
    cmd.duration_s = c.Require<double>("duration_s");
    c.Get("linear_mps", &cmd.linear_mps);
    c.Get("angular_radps", &cmd.angular_radps);
    c.Finish();
    commands.push_back(cmd);
  }
  return commands;
}

// One entry of `robots:`.
RobotSpec LoadRobot(common::YamlMap& r, const YAML::Node& node, const SimPaths& paths,
                    const SensorRegistry& sensors) {
  const std::string id = r.Require<std::string>("id");
  const std::string model = r.Require<std::string>("model");
  std::string profile;
  r.Get("profile", &profile);
  common::YamlMap spawn_map = r.Child("spawn");
  const SpawnPose spawn = LoadSpawn(spawn_map);
  RobotSpec spec;
  try {
    spec = MakeRobotSpec(id, model, profile, spawn, paths);
  } catch (const std::invalid_argument& e) {
    r.Fail(node, e.what());
  }
  if (r.Has("sensors")) {
    common::YamlMap map = r.Child("sensors");
    spec.sensors = LoadSensorSet(map, spec.model.default_sensors, sensors);
  }
  if (r.Has("commands")) spec.commands = LoadCommands(r);
  r.Finish();
  return spec;
}

}  // namespace

Scenario LoadScenario(common::YamlMap& map, const SimPaths& paths, const SensorRegistry& sensors) {
  Scenario s;
  s.world = map.Require<std::string>("world");
  s.world_path = ResolveWorld(map, s.world, paths);
  int64_t seed = 1;
  if (map.Get("seed", &seed) && seed < 0) map.Fail(map.Raw("seed"), "seed must be >= 0");
  s.seed = static_cast<uint64_t>(seed);
  {
    common::YamlMap physics = map.Child("physics");
    s.physics = LoadPhysicsParams(physics);
  }
  map.Get("ray_threads", &s.ray_threads);
  map.Get("spawn_slots", &s.spawn_slots);
  map.Get("clock_rate_hz", &s.clock_rate_hz);

  YAML::Node robots = map.Raw("robots");
  if (robots && !robots.IsSequence()) map.Fail(robots, "'robots' must be a list");
  int index = 0;
  for (const auto& node : robots) {
    common::YamlMap r = map.Wrap(node, "robots[" + std::to_string(index++) + "]");
    s.robots.push_back(LoadRobot(r, node, paths, sensors));
  }
  map.Finish();
  ValidateAt(map, [&] { s.Validate(); });
  return s;
}

Scenario LoadScenarioFile(const std::string& path, const SimPaths& paths,
                          const SensorRegistry& sensors) {
  common::YamlMap map = common::YamlMap::LoadFile(path);
  return LoadScenario(map, paths, sensors);
}

}  // namespace cairn::sim
