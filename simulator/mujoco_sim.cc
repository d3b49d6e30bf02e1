#include "simulator/mujoco_sim.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "common/check.h"
#include "simulator/mjcf_compose.h"

namespace cairn::sim {
namespace {

using Clock = std::chrono::steady_clock;
using common::Pose3;
using common::Quaternion;
using common::Status;
using common::Vector3;

constexpr double kParkedZ = -50.0;
// Wheel speed loop: integral gain (1/s) and the most it may add to a servo target (rad/s).
constexpr double kWheelIntegralGain = 8.0;
constexpr double kWheelIntegralLimit = 10.0;
constexpr char kDoorPrefix[] = "door_";

double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

int64_t ToUtime(double t_s) { return static_cast<int64_t>(std::llround(t_s * 1e6)); }

Eigen::Matrix3d RowMajor(const mjtNum* m) {
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(m);
}

Quaternion YawQuaternion(double yaw_rad) {
  return Quaternion(Eigen::AngleAxisd(yaw_rad, Vector3::UnitZ()));
}

// Sensor timing: reading n falls due at n / rate (n = 1, 2, ...), computed from integers so
// long runs do not drift.
struct Schedule {
  double rate_hz{1.0};
  int64_t count{0};
  bool Due(double now_s) const { return static_cast<double>(count + 1) / rate_hz <= now_s + 1e-9; }
};

int RequireId(const mjModel* m, mjtObj type, const std::string& name, const std::string& what) {
  const int id = mj_name2id(m, type, name.c_str());
  if (id < 0) throw std::invalid_argument(what + " '" + name + "' not found in the model");
  return id;
}

}  // namespace

void SimOutputs::Clear() {
  lidar.clear();
  scans.clear();
  turret_lines.clear();
  odometry.clear();
  poses.clear();
  imu.clear();
  events.clear();
}

bool SimOutputs::empty() const {
  return lidar.empty() && scans.empty() && turret_lines.empty() && odometry.empty() &&
         poses.empty() && imu.empty() && events.empty();
}

// ---------------------------------------------------------------------------------------------

struct MujocoSim::Robot {
  RobotSpec spec;
  int index{0};
  int root_body{-1};
  int qpos_adr{0};
  int qvel_adr{0};
  double base_height_m{0.0};  ///< base origin above the contact plane in the model file
  std::vector<int> left_actuators, right_actuators;
  std::vector<int> left_qpos, right_qpos;
  std::vector<int> left_dof, right_dof;
  /// Integral term of each wheel's speed loop (rad/s added to the servo target).
  std::vector<double> left_integral, right_integral;
  double left_angle{0.0}, right_angle{0.0};
  std::unique_ptr<DriveController> drive;
  std::unique_ptr<WheelOdometry> odometry;
  double odom_z_m{0.0};

  struct Lidar {
    LidarParams params;
    LidarPattern pattern;
    int site{-1};
    int64_t slices_done{0};
    std::vector<RayHit> hits;
    NoiseSource noise;
  };
  struct Planar {
    PlanarLaserParams params;
    RayPattern pattern;
    int site{-1};
    Schedule schedule;
    std::vector<RayHit> hits;
    NoiseSource noise;
  };
  struct Turret {
    TurretParams params;
    RayPattern pattern;
    int site{-1};
    int pan_steps{1};
    Schedule schedule;
    std::vector<RayHit> hits;
    NoiseSource noise;
  };
  struct Imu {
    ImuParams params;
    int gyro_adr{-1}, accel_adr{-1}, quat_adr{-1};
    Schedule schedule;
    NoiseSource noise;
  };
  std::unique_ptr<Lidar> lidar;
  std::unique_ptr<Planar> planar;
  std::unique_ptr<Turret> turret;
  std::unique_ptr<Imu> imu;
  Schedule odom_schedule;
  Schedule pose_schedule;
  bool has_odometry{false}, has_pose{false};
};

struct MujocoSim::Object {
  std::string name;
  int mocap{-1};           ///< a mocap body of the world (moved through mocap_pos), or
  int slot_geom{-1};       ///< a spawn-pool geom of the world body (moved through geom_pos)
  std::vector<int> geoms;  ///< geoms enabled while the object exists
};

// ---------------------------------------------------------------------------------------------

MujocoSim::MujocoSim(const Scenario& scenario) : scenario_(scenario) {
  scenario_.Validate();
  InstallMujocoLogHooks();

  // Compose and compile.
  std::vector<RobotInsertion> insertions;
  for (const RobotSpec& r : scenario_.robots) {
    insertions.push_back({r.id, r.model.xml, r.model.xml_path});
  }
  const std::string world_xml =
      scenario_.world_xml.empty() ? ReadTextFile(scenario_.world_path) : scenario_.world_xml;
  try {
    composed_xml_ =
        ComposeScene(world_xml, scenario_.world_path, insertions, scenario_.spawn_slots);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
  model_ = LoadModelFromText(composed_xml_, scenario_.world_path);
  mjModel* m = model_.get();
  m->opt.timestep = scenario_.physics.timestep_s;
  const std::string& integ = scenario_.physics.integrator;
  m->opt.integrator = integ == "rk4"        ? mjINT_RK4
                      : integ == "implicit" ? mjINT_IMPLICIT
                                            : mjINT_EULER;
  data_.reset(mj_makeData(m));
  if (!data_) throw std::runtime_error(scenario_.world_path + ": MuJoCo could not allocate data");

  scene_ = std::make_unique<RayScene>(m);
  if (scenario_.ray_threads > 1) pool_ = std::make_unique<ThreadPool>(scenario_.ray_threads);
  caster_ = std::make_unique<RayCaster>(pool_.get());

  // Intensity of a return: brightness of the surface colour, 0..100.
  intensity_.resize(m->ngeom);
  for (int g = 0; g < m->ngeom; ++g) {
    const int mat = m->geom_matid[g];
    const float* rgba = mat >= 0 ? m->mat_rgba + 4 * mat : m->geom_rgba + 4 * g;
    intensity_[g] = 100.f * (0.299f * rgba[0] + 0.587f * rgba[1] + 0.114f * rgba[2]);
  }

  // Spawn pool slots start parked and invisible.
  for (int k = 0; k < scenario_.spawn_slots; ++k) {
    const std::string name = std::string(kSpawnGeomPrefix) + std::to_string(k);
    const int geom = RequireId(m, mjOBJ_GEOM, name, "spawn slot");
    scene_->SetVisible(geom, false);
    free_slots_.push_back(geom);
  }
  std::reverse(free_slots_.begin(), free_slots_.end());
  // World mocap bodies (movable furniture) are addressable objects.
  for (int b = 1; b < m->nbody; ++b) {
    if (m->body_mocapid[b] < 0) continue;
    const std::string name = MjName(m, mjOBJ_BODY, b);
    if (name.empty()) continue;
    auto object = std::make_unique<Object>();
    object->name = name;
    object->mocap = m->body_mocapid[b];
    for (int g = 0; g < m->ngeom; ++g) {
      if (m->geom_bodyid[g] == b) object->geoms.push_back(g);
    }
    objects_[name] = std::move(object);
  }

  // Doors start open: the position servo's target and the hinge itself.
  for (const std::string& door : DoorNames()) {
    SetDoor(door, true);
    const int act = mj_name2id(m, mjOBJ_ACTUATOR, (std::string(kDoorPrefix) + door).c_str());
    data_->qpos[m->jnt_qposadr[m->actuator_trnid[2 * act]]] = data_->ctrl[act];
  }
  mj_forward(m, data_.get());
  for (size_t i = 0; i < scenario_.robots.size(); ++i) {
    auto robot = std::make_unique<Robot>();
    robot->spec = scenario_.robots[i];
    robots_.push_back(std::move(robot));
    SetupRobot(*robots_.back(), static_cast<int>(i));
  }
  mj_forward(m, data_.get());
  for (auto& robot : robots_) {
    robot->left_angle = robot->right_angle = 0.0;
    for (int a : robot->left_qpos) robot->left_angle += data_->qpos[a];
    for (int a : robot->right_qpos) robot->right_angle += data_->qpos[a];
    robot->left_angle /= static_cast<double>(robot->left_qpos.size());
    robot->right_angle /= static_cast<double>(robot->right_qpos.size());
  }
  scene_dirty_ = true;
}

MujocoSim::~MujocoSim() = default;

void MujocoSim::SetupRobot(Robot& robot, int index) {
  const mjModel* m = model_.get();
  const RobotSpec& spec = robot.spec;
  const std::string prefix = spec.id + "/";
  const std::string where = "robot '" + spec.id + "' (" + spec.model.xml_path + "): ";
  robot.index = index;

  // The root body is the one holding the free joint.
  int root = -1;
  for (int j = 0; j < m->njnt; ++j) {
    if (m->jnt_type[j] != mjJNT_FREE) continue;
    const std::string name = MjName(m, mjOBJ_JOINT, j);
    if (name.rfind(prefix, 0) == 0) {
      root = m->jnt_bodyid[j];
      robot.qpos_adr = m->jnt_qposadr[j];
      robot.qvel_adr = m->jnt_dofadr[j];
      break;
    }
  }
  if (root < 0) throw std::invalid_argument(where + "the model has no free joint");
  robot.root_body = root;
  robot.base_height_m = m->body_pos[3 * root + 2];

  // Its geoms are its own: excluded from its sensors, visible to others.
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->body_rootid[m->geom_bodyid[g]] == root) scene_->SetOwner(g, index);
  }

  // Wheels: hinge joints with velocity actuators of the same name.
  auto wheels = [&](const std::vector<std::string>& names, std::vector<int>* actuators,
                    std::vector<int>* qpos, std::vector<int>* dof) {
    for (const std::string& wheel : names) {
      const int joint = RequireId(m, mjOBJ_JOINT, prefix + wheel, where + "wheel joint");
      const int act = RequireId(m, mjOBJ_ACTUATOR, prefix + wheel, where + "wheel actuator");
      if (m->jnt_type[joint] != mjJNT_HINGE) {
        throw std::invalid_argument(where + "wheel joint '" + wheel + "' is not a hinge");
      }
      actuators->push_back(act);
      qpos->push_back(m->jnt_qposadr[joint]);
      dof->push_back(m->jnt_dofadr[joint]);
    }
  };
  wheels(spec.model.left_wheels, &robot.left_actuators, &robot.left_qpos, &robot.left_dof);
  wheels(spec.model.right_wheels, &robot.right_actuators, &robot.right_qpos, &robot.right_dof);
  robot.left_integral.assign(robot.left_dof.size(), 0.0);
  robot.right_integral.assign(robot.right_dof.size(), 0.0);
  robot.drive = std::make_unique<DriveController>(common::VelocityLimits::FromProfile(spec.profile),
                                                  spec.model.wheel_radius_m, spec.model.track_m);

  const uint64_t seed = scenario_.seed;
  const SensorSet& sensors = spec.sensors;
  auto site_id = [&](const std::string& site, const char* sensor) {
    const int id = mj_name2id(m, mjOBJ_SITE, (prefix + site).c_str());
    if (id < 0) {
      throw std::invalid_argument(where + "sensor '" + sensor + "' needs a site named '" + site +
                                  "' on the robot");
    }
    return id;
  };

  if (sensors.lidar) {
    auto lidar = std::make_unique<Robot::Lidar>();
    lidar->params = *sensors.lidar;
    lidar->pattern = BuildLidarPattern(lidar->params);
    lidar->site = site_id(lidar->params.mount_site, kSensorLidar);
    lidar->hits.resize(lidar->pattern.rays.directions.size());
    lidar->noise = NoiseSource(seed, NoiseStream(spec.id + "/" + kSensorLidar));
    robot.lidar = std::move(lidar);
  }
  if (sensors.planar_laser) {
    auto planar = std::make_unique<Robot::Planar>();
    planar->params = *sensors.planar_laser;
    planar->pattern = BuildFanPattern(planar->params.fov_deg, planar->params.beams);
    planar->site = site_id(planar->params.mount_site, kSensorPlanarLaser);
    planar->schedule.rate_hz = planar->params.rate_hz;
    planar->hits.resize(planar->pattern.directions.size());
    planar->noise = NoiseSource(seed, NoiseStream(spec.id + "/" + kSensorPlanarLaser));
    robot.planar = std::move(planar);
  }
  if (sensors.turret) {
    auto turret = std::make_unique<Robot::Turret>();
    turret->params = *sensors.turret;
    turret->pattern = BuildFanPattern(turret->params.fan_fov_deg, turret->params.fan_beams);
    turret->site = site_id(turret->params.mount_site, kSensorTurret);
    turret->pan_steps = std::max(1, static_cast<int>(std::lround(turret->params.pan_range_deg /
                                                                 turret->params.pan_step_deg)));
    turret->schedule.rate_hz = turret->params.line_rate_hz;
    turret->hits.resize(turret->pattern.directions.size());
    turret->noise = NoiseSource(seed, NoiseStream(spec.id + "/" + kSensorTurret));
    robot.turret = std::move(turret);
  }
  if (sensors.imu) {
    auto imu = std::make_unique<Robot::Imu>();
    imu->params = *sensors.imu;
    const int site = site_id(imu->params.site, kSensorImu);
    for (int s = 0; s < m->nsensor; ++s) {
      if (m->sensor_objtype[s] != mjOBJ_SITE || m->sensor_objid[s] != site) continue;
      if (m->sensor_type[s] == mjSENS_GYRO) imu->gyro_adr = m->sensor_adr[s];
      if (m->sensor_type[s] == mjSENS_ACCELEROMETER) imu->accel_adr = m->sensor_adr[s];
      if (m->sensor_type[s] == mjSENS_FRAMEQUAT) imu->quat_adr = m->sensor_adr[s];
    }
    if (imu->gyro_adr < 0 || imu->accel_adr < 0 || imu->quat_adr < 0) {
      throw std::invalid_argument(where +
                                  "sensor 'imu' needs gyro, accelerometer and framequat "
                                  "sensors on site '" +
                                  imu->params.site + "'");
    }
    imu->schedule.rate_hz = imu->params.rate_hz;
    imu->noise = NoiseSource(seed, NoiseStream(spec.id + "/" + kSensorImu));
    robot.imu = std::move(imu);
  }
  OdometryParams odom_params = sensors.odometry.value_or(OdometryParams{});
  robot.has_odometry = sensors.odometry.has_value();
  robot.odom_schedule.rate_hz = odom_params.rate_hz;
  robot.odometry = std::make_unique<WheelOdometry>(
      odom_params, spec.model.wheel_radius_m, spec.model.track_m,
      NoiseSource(seed, NoiseStream(spec.id + "/" + kSensorOdometry)));
  robot.has_pose = sensors.ground_truth.has_value();
  robot.pose_schedule.rate_hz = sensors.ground_truth.value_or(GroundTruthParams{}).rate_hz;

  PlaceRobot(robot, spec.spawn.x_m, spec.spawn.y_m, spec.spawn.yaw_rad, spec.spawn.z_m);
}

double MujocoSim::GroundHeight(double x_m, double y_m) const {
  // Highest sensor-visible surface below 10 m, robots excluded (groups 0-2).
  static const mjtByte kGroups[mjNGROUP] = {1, 1, 1, 0, 0, 0};
  const double origin[3] = {x_m, y_m, 10.0};
  const double down[3] = {0.0, 0.0, -1.0};
  int geom = -1;
  const double d = mj_ray(model_.get(), data_.get(), origin, down, kGroups, 1, -1, &geom);
  return d >= 0.0 ? origin[2] - d : 0.0;
}

void MujocoSim::PlaceRobot(Robot& robot, double x_m, double y_m, double yaw_rad,
                           std::optional<double> z_m) {
  mjData* d = data_.get();
  const double z = z_m ? *z_m : GroundHeight(x_m, y_m) + robot.base_height_m + 0.005;
  double* q = d->qpos + robot.qpos_adr;
  const Quaternion quat = YawQuaternion(yaw_rad);
  q[0] = x_m;
  q[1] = y_m;
  q[2] = z;
  q[3] = quat.w();
  q[4] = quat.x();
  q[5] = quat.y();
  q[6] = quat.z();
  for (int i = 0; i < 6; ++i) d->qvel[robot.qvel_adr + i] = 0.0;
  robot.drive->Halt();
  std::fill(robot.left_integral.begin(), robot.left_integral.end(), 0.0);
  std::fill(robot.right_integral.begin(), robot.right_integral.end(), 0.0);
  robot.odometry->Reset({x_m, y_m, yaw_rad});
  robot.odom_z_m = z;
  mj_kinematics(model_.get(), d);
  scene_dirty_ = true;
}

// ---------------------------------------------------------------------------------------------

double MujocoSim::time_s() const { return data_->time; }
int64_t MujocoSim::utime() const { return ToUtime(data_->time); }
double MujocoSim::timestep_s() const { return model_->opt.timestep; }

std::vector<std::string> MujocoSim::robot_ids() const {
  std::vector<std::string> ids;
  for (const auto& r : robots_) ids.push_back(r->spec.id);
  return ids;
}

bool MujocoSim::HasRobot(const std::string& id) const {
  for (const auto& r : robots_) {
    if (r->spec.id == id) return true;
  }
  return false;
}

MujocoSim::Robot& MujocoSim::FindRobot(const std::string& id) {
  for (auto& r : robots_) {
    if (r->spec.id == id) return *r;
  }
  throw std::invalid_argument("unknown robot '" + id + "'");
}

const MujocoSim::Robot& MujocoSim::FindRobot(const std::string& id) const {
  return const_cast<MujocoSim*>(this)->FindRobot(id);
}

CommandVerdict MujocoSim::Command(const std::string& robot, double linear_mps,
                                  double angular_radps) {
  return FindRobot(robot).drive->SetCommand(linear_mps, angular_radps, data_->time);
}

const DriveController& MujocoSim::drive(const std::string& robot) const {
  return *FindRobot(robot).drive;
}

common::Pose2 MujocoSim::OdometryPose(const std::string& robot) const {
  return FindRobot(robot).odometry->pose();
}

Pose3 MujocoSim::RobotPose(const std::string& id) const {
  const Robot& r = FindRobot(id);
  const double* q = data_->qpos + r.qpos_adr;
  Pose3 pose;
  pose.position_m = Vector3(q[0], q[1], q[2]);
  pose.orientation = Quaternion(q[3], q[4], q[5], q[6]).normalized();
  return pose;
}

Vector3 MujocoSim::RobotVelocity(const std::string& id) const {
  const Robot& r = FindRobot(id);
  const double* v = data_->qvel + r.qvel_adr;
  return Vector3(v[0], v[1], v[2]);
}

Status MujocoSim::ResetRobot(const std::string& id, double x_m, double y_m, double yaw_rad,
                             std::optional<double> z_m) {
  if (!HasRobot(id)) return common::NotFoundError("no robot '" + id + "'");
  if (!std::isfinite(x_m) || !std::isfinite(y_m) || !std::isfinite(yaw_rad) ||
      (z_m && !std::isfinite(*z_m))) {
    return common::InvalidArgumentError("reset pose must be finite");
  }
  PlaceRobot(FindRobot(id), x_m, y_m, yaw_rad, z_m);
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// Stepping

void MujocoSim::Step(SimOutputs* out) {
  const double dt = model_->opt.timestep;
  const auto t0 = Clock::now();
  ApplyDrive(data_->time, dt, out);
  mj_step(model_.get(), data_.get());
  ++stats_.physics_steps;
  IntegrateOdometry(dt);
  const auto t1 = Clock::now();
  stats_.physics_s += Seconds(t0, t1);
  scene_dirty_ = true;
  ProduceReadings(out);
  stats_.sensors_s += Seconds(t1, Clock::now());
}

void MujocoSim::ApplyDrive(double now_s, double dt_s, SimOutputs* out) {
  mjData* d = data_.get();
  for (auto& r : robots_) {
    for (const ScriptedCommand& c : r->spec.commands) {
      if (now_s >= c.at_s && now_s < c.at_s + c.duration_s) {
        r->drive->SetCommand(c.linear_mps, c.angular_radps, now_s);
      }
    }
    if (r->drive->Update(now_s, dt_s)) {
      out->events.push_back("watchdog stopped robot '" + r->spec.id +
                            "': no velocity command for 0.5 s of sim time");
    }
    // Each wheel runs a PI speed loop, like motor firmware: the MJCF velocity servo is the P
    // part, the integral of the speed error raises its target until the wheel keeps up under
    // load (skid-steer turning, slopes) and holds a parked robot still.
    auto servo = [&](const std::vector<int>& actuators, const std::vector<int>& dofs,
                     std::vector<double>& integral, double target) {
      for (size_t i = 0; i < actuators.size(); ++i) {
        const double error = target - d->qvel[dofs[i]];
        integral[i] = std::clamp(integral[i] + kWheelIntegralGain * error * dt_s,
                                 -kWheelIntegralLimit, kWheelIntegralLimit);
        d->ctrl[actuators[i]] = target + integral[i];
      }
    };
    servo(r->left_actuators, r->left_dof, r->left_integral, r->drive->left_wheel_radps());
    servo(r->right_actuators, r->right_dof, r->right_integral, r->drive->right_wheel_radps());
  }
}

void MujocoSim::IntegrateOdometry(double dt_s) {
  const double* q = data_->qpos;
  for (auto& r : robots_) {
    double left = 0.0, right = 0.0;
    for (int a : r->left_qpos) left += q[a];
    for (int a : r->right_qpos) right += q[a];
    left /= static_cast<double>(r->left_qpos.size());
    right /= static_cast<double>(r->right_qpos.size());
    r->odometry->Integrate(left - r->left_angle, right - r->right_angle, dt_s);
    r->left_angle = left;
    r->right_angle = right;
  }
}

Pose3 MujocoSim::SitePose(int site) const {
  Pose3 pose;
  pose.position_m = Vector3(data_->site_xpos[3 * site], data_->site_xpos[3 * site + 1],
                            data_->site_xpos[3 * site + 2]);
  pose.orientation = Quaternion(RowMajor(data_->site_xmat + 9 * site)).normalized();
  return pose;
}

void MujocoSim::ProduceReadings(SimOutputs* out) {
  const double now = data_->time;
  const int64_t utime = ToUtime(now);

  // Which sensors fall due at this step. Ray sensors need the poses of everything at `now`
  // (mj_step leaves the positions of the step's start in x*); the others read qpos, qvel and
  // sensordata directly.
  bool any_due = false, rays_due = false;
  for (const auto& r : robots_) {
    if (r->lidar) {
      const auto& p = r->lidar->params;
      const double next =
          static_cast<double>(r->lidar->slices_done + 1) / (p.rate_hz * p.slices_per_revolution);
      rays_due |= next <= now + 1e-9;
    }
    rays_due |=
        (r->planar && r->planar->schedule.Due(now)) || (r->turret && r->turret->schedule.Due(now));
    any_due |= (r->imu && r->imu->schedule.Due(now)) ||
               (r->has_odometry && r->odom_schedule.Due(now)) ||
               (r->has_pose && r->pose_schedule.Due(now));
  }
  if (!any_due && !rays_due) return;
  if (rays_due) mj_kinematics(model_.get(), data_.get());

  for (auto& r : robots_) {
    if (r->lidar) CastLidar(*r, out);
    if (r->planar && r->planar->schedule.Due(now)) {
      while (r->planar->schedule.Due(now)) ++r->planar->schedule.count;
      CastPlanar(*r, out);
    }
    if (r->turret && r->turret->schedule.Due(now)) {
      while (r->turret->schedule.Due(now)) ++r->turret->schedule.count;
      CastTurret(*r, out);
    }
    const double* q = data_->qpos + r->qpos_adr;
    const double* v = data_->qvel + r->qvel_adr;
    const Quaternion base_q = Quaternion(q[3], q[4], q[5], q[6]).normalized();
    if (r->has_pose && r->pose_schedule.Due(now)) {
      while (r->pose_schedule.Due(now)) ++r->pose_schedule.count;
      GroundTruthReading g;
      g.utime = utime;
      g.robot = r->spec.id;
      g.pose.position_m = Vector3(q[0], q[1], q[2]);
      g.pose.orientation = base_q;
      // Free joint: linear velocity in the world frame, angular in the body frame.
      g.linear_velocity_mps = Vector3(v[0], v[1], v[2]);
      g.angular_velocity_radps = base_q * Vector3(v[3], v[4], v[5]);
      out->poses.push_back(g);
    }
    if (r->has_odometry && r->odom_schedule.Due(now)) {
      while (r->odom_schedule.Due(now)) ++r->odom_schedule.count;
      OdometryReading o;
      o.utime = utime;
      o.robot = r->spec.id;
      const common::Pose2& p = r->odometry->pose();
      o.pose.position_m = Vector3(p.x_m, p.y_m, r->odom_z_m);
      o.pose.orientation = YawQuaternion(p.yaw_rad);
      o.linear_velocity_mps = Vector3(r->odometry->linear_mps(), 0.0, 0.0);
      o.angular_velocity_radps = Vector3(0.0, 0.0, r->odometry->angular_radps());
      out->odometry.push_back(o);
    }
    if (r->imu && r->imu->schedule.Due(now)) {
      auto& imu = *r->imu;
      const uint64_t n = static_cast<uint64_t>(imu.schedule.count) * 16;
      while (imu.schedule.Due(now)) ++imu.schedule.count;
      const auto& p = imu.params;
      const double* s = data_->sensordata;
      ImuReading reading;
      reading.utime = utime;
      reading.robot = r->spec.id;
      for (int i = 0; i < 3; ++i) {
        reading.angular_velocity_radps[i] =
            s[imu.gyro_adr + i] + p.gyro_noise_sigma_radps * imu.noise.Gaussian(n + i);
        reading.linear_acceleration_mps2[i] =
            s[imu.accel_adr + i] + p.accel_noise_sigma_mps2 * imu.noise.Gaussian(n + 3 + i);
      }
      const Quaternion truth(s[imu.quat_adr], s[imu.quat_adr + 1], s[imu.quat_adr + 2],
                             s[imu.quat_adr + 3]);
      const Vector3 tilt(imu.noise.Gaussian(n + 6), imu.noise.Gaussian(n + 7),
                         imu.noise.Gaussian(n + 8));
      const Vector3 error = p.orientation_noise_sigma_rad * tilt;
      const double angle = error.norm();
      const Quaternion noise_q = angle > 0.0 ? Quaternion(Eigen::AngleAxisd(angle, error / angle))
                                             : Quaternion::Identity();
      reading.orientation = (truth.normalized() * noise_q).normalized();
      reading.orientation_variance_rad2 =
          p.orientation_noise_sigma_rad * p.orientation_noise_sigma_rad;
      reading.angular_velocity_variance = p.gyro_noise_sigma_radps * p.gyro_noise_sigma_radps;
      reading.linear_acceleration_variance = p.accel_noise_sigma_mps2 * p.accel_noise_sigma_mps2;
      out->imu.push_back(reading);
    }
  }
}

void MujocoSim::CastPattern(const Robot& robot, const Pose3& sensor, const RayPattern& pattern,
                            int group_begin, int group_end, double max_range_m,
                            std::vector<RayHit>* hits) {
  const auto t0 = Clock::now();
  if (scene_dirty_) {
    scene_->Update(data_.get());
    scene_dirty_ = false;
  }
  const Eigen::Matrix3d rotation = sensor.orientation.toRotationMatrix();
  if (use_mj_ray_) {
    RayCaster::CastWithMjRay(model_.get(), data_.get(), sensor.position_m, rotation, pattern,
                             group_begin, group_end, max_range_m, hits->data());
  } else {
    caster_->Cast(*scene_, data_.get(), sensor.position_m, rotation, pattern, group_begin,
                  group_end, max_range_m, robot.index, hits->data());
  }
  const int first = pattern.groups[group_begin].begin;
  const int last = pattern.groups[group_end - 1].end;
  stats_.rays_cast += last - first;
  stats_.ray_s += Seconds(t0, Clock::now());
}

void MujocoSim::CastLidar(Robot& robot, SimOutputs* out) {
  auto& lidar = *robot.lidar;
  const LidarParams& p = lidar.params;
  const double now = data_->time;
  const int slices = p.slices_per_revolution;
  const RayPattern& rays = lidar.pattern.rays;
  const int rays_per_rev = static_cast<int>(rays.directions.size());
  while (static_cast<double>(lidar.slices_done + 1) / (p.rate_hz * slices) <= now + 1e-9) {
    const int64_t revolution = lidar.slices_done / slices;
    const int slice = static_cast<int>(lidar.slices_done % slices);
    ++lidar.slices_done;
    const Pose3 sensor = SitePose(lidar.site);
    const int g0 = lidar.pattern.slice_group_begin[slice];
    const int g1 = lidar.pattern.slice_group_begin[slice + 1];
    if (g1 <= g0) continue;
    CastPattern(robot, sensor, rays, g0, g1, p.max_range_m, &lidar.hits);

    common::LidarSlice s;
    s.utime = ToUtime(now);
    s.robot = robot.spec.id;
    s.revolution = revolution;
    s.slice_index = slice;
    s.slice_count = slices;
    s.azimuth_start_rad = LidarAzimuthRad(p, LidarSliceBegin(p, slice));
    s.azimuth_end_rad = LidarAzimuthRad(p, LidarSliceBegin(p, slice + 1));
    s.max_range_m = p.max_range_m;
    s.sensor_pose = sensor;
    const int first = lidar.pattern.slice_ray_begin[slice];
    const int last = lidar.pattern.slice_ray_begin[slice + 1];
    s.points.reserve(last - first);
    const uint64_t noise_base = static_cast<uint64_t>(revolution) * rays_per_rev;
    for (int i = first; i < last; ++i) {
      const RayHit& h = lidar.hits[i];
      if (h.geom < 0) continue;
      double range = h.range_m;
      if (p.range_noise_sigma_m > 0.0) {
        range += p.range_noise_sigma_m * lidar.noise.Gaussian(noise_base + i);
      }
      if (range < p.min_range_m || range > p.max_range_m) continue;
      const Eigen::Vector3d& dir = rays.directions[i];
      common::LidarPoint point;
      point.x_m = static_cast<float>(dir.x() * range);
      point.y_m = static_cast<float>(dir.y() * range);
      point.z_m = static_cast<float>(dir.z() * range);
      point.intensity = intensity_[h.geom];
      point.ring = lidar.pattern.ring[i];
      s.points.push_back(point);
    }
    out->lidar.push_back(std::move(s));
  }
}

void MujocoSim::CastPlanar(Robot& robot, SimOutputs* out) {
  auto& planar = *robot.planar;
  const PlanarLaserParams& p = planar.params;
  const Pose3 sensor = SitePose(planar.site);
  CastPattern(robot, sensor, planar.pattern, 0, static_cast<int>(planar.pattern.groups.size()),
              p.max_range_m, &planar.hits);
  common::LaserScan scan;
  scan.utime = utime();
  scan.robot = robot.spec.id;
  scan.sensor_pose = sensor;
  FanAngles(p.fov_deg, p.beams, &scan.angle_min_rad, &scan.angle_increment_rad);
  scan.range_min_m = p.min_range_m;
  scan.range_max_m = p.max_range_m;
  scan.ranges_m.resize(p.beams);
  scan.intensities.resize(p.beams);
  const uint64_t base = static_cast<uint64_t>(planar.schedule.count) * p.beams;
  for (int i = 0; i < p.beams; ++i) {
    const RayHit& h = planar.hits[i];
    float range = std::numeric_limits<float>::infinity();
    float intensity = 0.f;
    if (h.geom >= 0) {
      double r = h.range_m + p.range_noise_sigma_m * planar.noise.Gaussian(base + i);
      if (r > p.max_range_m) {
        r = std::numeric_limits<double>::infinity();
      } else if (r < p.min_range_m) {
        r = std::numeric_limits<double>::quiet_NaN();  // too close to measure
      } else {
        intensity = intensity_[h.geom];
      }
      range = static_cast<float>(r);
    }
    scan.ranges_m[i] = range;
    scan.intensities[i] = intensity;
  }
  out->scans.push_back(std::move(scan));
}

void MujocoSim::CastTurret(Robot& robot, SimOutputs* out) {
  auto& turret = *robot.turret;
  const TurretParams& p = turret.params;
  const int64_t line = turret.schedule.count - 1;
  const int step = static_cast<int>(line % turret.pan_steps);
  const double pan = step * p.pan_step_deg * M_PI / 180.0;
  const Pose3 mount = SitePose(turret.site);
  Pose3 sensor;
  sensor.position_m = mount.position_m;
  sensor.orientation = (mount.orientation * Quaternion(TurretLineRotation(pan))).normalized();
  CastPattern(robot, sensor, turret.pattern, 0, static_cast<int>(turret.pattern.groups.size()),
              p.max_range_m, &turret.hits);
  TurretLine out_line;
  out_line.pan_rad = pan;
  out_line.line = line;
  common::LaserScan& scan = out_line.scan;
  scan.utime = utime();
  scan.robot = robot.spec.id;
  scan.sensor_pose = sensor;
  FanAngles(p.fan_fov_deg, p.fan_beams, &scan.angle_min_rad, &scan.angle_increment_rad);
  scan.range_min_m = p.min_range_m;
  scan.range_max_m = p.max_range_m;
  scan.ranges_m.resize(p.fan_beams);
  scan.intensities.resize(p.fan_beams);
  const uint64_t base = static_cast<uint64_t>(line) * p.fan_beams;
  for (int i = 0; i < p.fan_beams; ++i) {
    const RayHit& h = turret.hits[i];
    float range = std::numeric_limits<float>::infinity();
    float intensity = 0.f;
    if (h.geom >= 0) {
      double r = h.range_m + p.range_noise_sigma_m * turret.noise.Gaussian(base + i);
      if (r > p.max_range_m) {
        r = std::numeric_limits<double>::infinity();
      } else if (r < p.min_range_m) {
        r = std::numeric_limits<double>::quiet_NaN();
      } else {
        intensity = intensity_[h.geom];
      }
      range = static_cast<float>(r);
    }
    scan.ranges_m[i] = range;
    scan.intensities[i] = intensity;
  }
  out->turret_lines.push_back(std::move(out_line));
}

// ---------------------------------------------------------------------------------------------
// Objects and doors

void MujocoSim::SetGeomEnabled(int geom, bool enabled) {
  mjModel* m = model_.get();
  m->geom_contype[geom] = enabled ? 1 : 0;
  m->geom_conaffinity[geom] = enabled ? 1 : 0;
  m->geom_group[geom] = enabled ? 0 : kParkedGeomGroup;
  scene_->SetVisible(geom, enabled);
  scene_dirty_ = true;
}

MujocoSim::Object* MujocoSim::FindObject(const std::string& name) {
  auto it = objects_.find(name);
  return it == objects_.end() ? nullptr : it->second.get();
}

Status MujocoSim::SpawnObject(const ObjectSpec& spec) {
  if (spec.name.empty()) return common::InvalidArgumentError("an object needs a name");
  if (FindObject(spec.name) != nullptr || HasRobot(spec.name)) {
    return common::AlreadyExistsError("an object named '" + spec.name + "' already exists");
  }
  const int dims = spec.shape == ObjectShape::kBox        ? 3
                   : spec.shape == ObjectShape::kCylinder ? 2
                                                          : 1;
  for (int i = 0; i < dims; ++i) {
    if (!std::isfinite(spec.size_m[i]) || spec.size_m[i] <= 0.0 || spec.size_m[i] > 50.0) {
      return common::InvalidArgumentError("object sizes must be in (0, 50] m");
    }
  }
  if (!spec.position_m.allFinite() || !std::isfinite(spec.yaw_rad)) {
    return common::InvalidArgumentError("object position and yaw must be finite");
  }
  if (free_slots_.empty()) {
    return common::ResourceExhaustedError("all " + std::to_string(scenario_.spawn_slots) +
                                          " spawn slots are in use");
  }
  mjModel* m = model_.get();
  const int geom = free_slots_.back();
  free_slots_.pop_back();
  // Primitive geoms may change type, size and pose at run time: kinematics, collision and ray
  // functions read them from the model on every call. The bounding radius must follow.
  m->geom_type[geom] = spec.shape == ObjectShape::kBox        ? mjGEOM_BOX
                       : spec.shape == ObjectShape::kCylinder ? mjGEOM_CYLINDER
                                                              : mjGEOM_SPHERE;
  double* size = m->geom_size + 3 * geom;
  switch (spec.shape) {
    case ObjectShape::kBox:
      for (int i = 0; i < 3; ++i) size[i] = spec.size_m[i];
      m->geom_rbound[geom] = spec.size_m.norm();
      break;
    case ObjectShape::kCylinder:
      size[0] = spec.size_m[0];
      size[1] = spec.size_m[1];
      m->geom_rbound[geom] = std::hypot(spec.size_m[0], spec.size_m[1]);
      break;
    case ObjectShape::kSphere:
      size[0] = spec.size_m[0];
      m->geom_rbound[geom] = spec.size_m[0];
      break;
  }
  SetGeomEnabled(geom, true);
  auto object = std::make_unique<Object>();
  object->name = spec.name;
  object->slot_geom = geom;
  object->geoms = {geom};
  objects_[spec.name] = std::move(object);
  return MoveObject(spec.name, spec.position_m, spec.yaw_rad);
}

Status MujocoSim::MoveObject(const std::string& name, const Vector3& position_m, double yaw_rad) {
  Object* object = FindObject(name);
  if (object == nullptr) return common::NotFoundError("no object '" + name + "'");
  if (!position_m.allFinite() || !std::isfinite(yaw_rad)) {
    return common::InvalidArgumentError("object position and yaw must be finite");
  }
  mjData* d = data_.get();
  mjModel* m = model_.get();
  const Quaternion q = YawQuaternion(yaw_rad);
  // A pool geom hangs off the world body, so its pose in the model is its world pose.
  double* pos = object->slot_geom >= 0 ? m->geom_pos + 3 * object->slot_geom
                                       : d->mocap_pos + 3 * object->mocap;
  double* quat = object->slot_geom >= 0 ? m->geom_quat + 4 * object->slot_geom
                                        : d->mocap_quat + 4 * object->mocap;
  for (int i = 0; i < 3; ++i) pos[i] = position_m[i];
  quat[0] = q.w();
  quat[1] = q.x();
  quat[2] = q.y();
  quat[3] = q.z();
  mj_kinematics(m, d);
  scene_dirty_ = true;
  return Status::Ok();
}

Status MujocoSim::RemoveObject(const std::string& name) {
  Object* object = FindObject(name);
  if (object == nullptr) return common::NotFoundError("no object '" + name + "'");
  for (int g : object->geoms) SetGeomEnabled(g, false);
  mjData* d = data_.get();
  if (object->slot_geom >= 0) {
    model_->geom_pos[3 * object->slot_geom + 2] = kParkedZ;
    free_slots_.push_back(object->slot_geom);
  } else {
    d->mocap_pos[3 * object->mocap + 2] = kParkedZ;
  }
  objects_.erase(name);
  mj_kinematics(model_.get(), d);
  scene_dirty_ = true;
  return Status::Ok();
}

std::vector<std::string> MujocoSim::DoorNames() const {
  std::vector<std::string> doors;
  const mjModel* m = model_.get();
  for (int a = 0; a < m->nu; ++a) {
    const std::string name = MjName(m, mjOBJ_ACTUATOR, a);
    if (name.rfind(kDoorPrefix, 0) != 0 || m->actuator_trntype[a] != mjTRN_JOINT) continue;
    doors.push_back(name.substr(std::string(kDoorPrefix).size()));
  }
  return doors;
}

Status MujocoSim::SetDoor(const std::string& name_in, bool open) {
  const mjModel* m = model_.get();
  const std::string name =
      name_in.rfind(kDoorPrefix, 0) == 0 ? name_in : std::string(kDoorPrefix) + name_in;
  const int act = mj_name2id(m, mjOBJ_ACTUATOR, name.c_str());
  if (act < 0 || m->actuator_trntype[act] != mjTRN_JOINT) {
    return common::NotFoundError("no door '" + name_in + "'");
  }
  const int joint = m->actuator_trnid[2 * act];
  double target = 0.0;
  if (open) {
    target = m->jnt_limited[joint] ? m->jnt_range[2 * joint + 1] : M_PI / 2;
    if (target == 0.0) target = m->jnt_range[2 * joint];  // doors that open the other way
  }
  data_->ctrl[act] = target;
  return Status::Ok();
}

std::vector<std::string> MujocoSim::ObjectNames() const {
  std::vector<std::string> names;
  for (const auto& [name, object] : objects_) names.push_back(name);
  return names;
}

std::vector<std::string> MujocoSim::ListNames() const {
  std::vector<std::string> names;
  for (const auto& r : robots_) names.push_back("robot:" + r->spec.id);
  for (const auto& door : DoorNames()) names.push_back("door:" + door);
  for (const auto& object : ObjectNames()) names.push_back("object:" + object);
  return names;
}

}  // namespace cairn::sim
