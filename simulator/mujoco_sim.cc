#include "simulator/mujoco_sim.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "common/check.h"
#include "common/log.h"
#include "simulator/mjcf_compose.h"
#include "simulator/model_capacity.h"
#include "simulator/sensor_registry.h"

namespace cairn::sim {
namespace {

using Clock = std::chrono::steady_clock;
using common::Pose3;
using common::Quaternion;
using common::Status;
using common::Vector3;

constexpr double kParkedZ = -50.0;
constexpr char kDoorPrefix[] = "door_";

double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

Quaternion YawQuaternion(double yaw_rad) {
  return Quaternion(Eigen::AngleAxisd(yaw_rad, Vector3::UnitZ()));
}

int RequireId(const mjModel* m, mjtObj type, const std::string& name, const std::string& what) {
  const int id = mj_name2id(m, type, name.c_str());
  if (id < 0) throw std::invalid_argument(what + " '" + name + "' not found in the model");
  return id;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

struct MujocoSim::Robot {
  RobotSpec spec;
  int index{0};
  int root_body{-1};
  int qpos_adr{0};
  int qvel_adr{0};
  double base_height_m{0.0};  ///< base origin above the contact plane in the model file
  std::unique_ptr<DriveController> drive;
  std::unique_ptr<DriveModel> drive_model;  ///< wheels or thrusters
  /// In the order of the robot's SensorSet.
  std::vector<std::unique_ptr<SimSensor>> sensors;
  std::vector<std::string> sensor_names;
};

struct MujocoSim::Object {
  std::string name;
  int mocap{-1};           ///< a mocap body of the world (moved through mocap_pos), or
  int slot_geom{-1};       ///< a spawn-pool geom of the world body (moved through geom_pos)
  std::vector<int> geoms;  ///< geoms enabled while the object exists
};

// ---------------------------------------------------------------------------------------------
// Construction

MujocoSim::MujocoSim(const Scenario& scenario) : scenario_(scenario) {
  scenario_.Validate();
  InstallMujocoLogHooks();
  Compose();
  rays_ = std::make_unique<SceneRays>(model_.get(), scenario_.ray_threads);
  SetupSpawnPool();
  CollectMocapObjects();
  OpenDoors();
  // Poses only (for placing robots on the surface): every robot is still at the model's origin,
  // on top of the others, and a collision pass there would fill the contact buffer for nothing.
  mj_kinematics(model_.get(), data_.get());
  SetupRobots();
  rays_->MarkMoved();
}

MujocoSim::~MujocoSim() = default;

void MujocoSim::Compose() {
  std::vector<RobotInsertion> insertions;
  for (const RobotSpec& r : scenario_.robots) {
    insertions.push_back({r.id, r.model.xml, r.model.xml_path});
  }
  const std::string world_xml =
      scenario_.world_xml.empty() ? ReadTextFile(scenario_.world_path) : scenario_.world_xml;
  std::string composed;
  try {
    composed = ComposeScene(world_xml, scenario_.world_path, insertions, scenario_.spawn_slots);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
  // Buffers sized for what the scene holds (model_capacity.h). MuJoCo's compiler makes an
  // mjData of the text's sizes, so it compiles with MuJoCo's small defaults (100 contacts, 500
  // rows) and the model then gets the sizes its contents need before the real mjData is made;
  // the composed text records them (compiling it gives the same model). Sizes the world's own
  // <size> element sets are kept.
  const SizeAttributes world_sizes = SizeAttributesOf(composed);
  ModelCapacity compile_sizes;
  compile_sizes.nconmax = 100;
  compile_sizes.njmax = 500;
  compile_sizes.nstack = -1;  // MuJoCo's rule for 500 rows: a few MB
  model_ = LoadModelFromText(WithSizes(composed, compile_sizes, world_sizes), scenario_.world_path,
                             /*placeholder_buffers=*/true);
  mjModel* m = model_.get();
  ModelCapacity sizes = ContactCapacity(m, kParkedGeomGroup);
  if (world_sizes.nconmax) sizes.nconmax = m->nconmax;
  if (world_sizes.njmax) sizes.njmax = m->njmax;
  sizes.nstack = world_sizes.nstack ? m->nstack : MujocoStackHeuristic(m, sizes.njmax);
  m->nconmax = sizes.nconmax;
  m->njmax = sizes.njmax;
  m->nstack = sizes.nstack;
  composed_xml_ = WithSizes(composed, sizes, world_sizes);
  m->opt.timestep = scenario_.physics.timestep_s;
  const std::string& integ = scenario_.physics.integrator;
  m->opt.integrator = integ == "rk4"        ? mjINT_RK4
                      : integ == "implicit" ? mjINT_IMPLICIT
                                            : mjINT_EULER;
  const PhysicsParams& physics = scenario_.physics;
  if (physics.current_x_mps != 0.0 || physics.current_y_mps != 0.0) {
    if (!(m->opt.density > 0.0)) {
      throw std::runtime_error(scenario_.world_path +
                               ": a current needs water (<option density=\"1000\"/>); this "
                               "world has none");
    }
    m->opt.wind[0] = physics.current_x_mps;
    m->opt.wind[1] = physics.current_y_mps;
  }
  data_.reset(mj_makeData(m));
  if (!data_) throw std::runtime_error(scenario_.world_path + ": MuJoCo could not allocate data");
}

void MujocoSim::SetupSpawnPool() {
  // Spawn pool slots start parked and invisible.
  for (int k = 0; k < scenario_.spawn_slots; ++k) {
    const std::string name = std::string(kSpawnGeomPrefix) + std::to_string(k);
    const int geom = RequireId(model_.get(), mjOBJ_GEOM, name, "spawn slot");
    rays_->scene().SetVisible(geom, false);
    free_slots_.push_back(geom);
  }
  std::reverse(free_slots_.begin(), free_slots_.end());
}

void MujocoSim::CollectMocapObjects() {
  // World mocap bodies (movable furniture) are addressable objects.
  const mjModel* m = model_.get();
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
}

void MujocoSim::OpenDoors() {
  // Doors start open: the position servo's target and the hinge itself.
  const mjModel* m = model_.get();
  for (const std::string& door : DoorNames()) {
    SetDoor(door, true);
    const int act = mj_name2id(m, mjOBJ_ACTUATOR, (std::string(kDoorPrefix) + door).c_str());
    data_->qpos[m->jnt_qposadr[m->actuator_trnid[2 * act]]] = data_->ctrl[act];
  }
}

void MujocoSim::SetupRobots() {
  for (size_t i = 0; i < scenario_.robots.size(); ++i) {
    auto robot = std::make_unique<Robot>();
    robot->spec = scenario_.robots[i];
    robots_.push_back(std::move(robot));
    SetupRobot(*robots_.back(), static_cast<int>(i));
  }
  mj_forward(model_.get(), data_.get());
  for (auto& robot : robots_) robot->drive_model->Reset(data_.get());
}

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
    if (m->body_rootid[m->geom_bodyid[g]] == root) rays_->scene().SetOwner(g, index);
  }
  DriveSite site;
  site.model = model_.get();
  site.robot = &robot.spec.model;
  site.prefix = prefix;
  site.where = where;
  site.root_body = root;
  site.qpos_adr = robot.qpos_adr;
  site.qvel_adr = robot.qvel_adr;
  robot.drive_model = MakeDriveModel(site);
  robot.drive = std::make_unique<DriveController>(common::VelocityLimits::FromProfile(spec.profile),
                                                  spec.model.wheel_radius_m, spec.model.track_m);
  CreateSensors(robot);
  PlaceRobot(robot, spec.spawn.x_m, spec.spawn.y_m, spec.spawn.yaw_rad, spec.spawn.z_m);
}

void MujocoSim::CreateSensors(Robot& robot) {
  SensorContext context;
  context.model = model_.get();
  context.robot = robot.spec.id;
  context.robot_index = robot.index;
  context.model_path = robot.spec.model.xml_path;
  context.qpos_adr = robot.qpos_adr;
  context.qvel_adr = robot.qvel_adr;
  context.wheel_radius_m = robot.spec.model.wheel_radius_m;
  context.track_m = robot.spec.model.track_m;
  context.seed = scenario_.seed;
  for (const SensorSet::Entry& entry : robot.spec.sensors.entries()) {
    context.sensor = entry.kind->name;
    robot.sensors.push_back(entry.kind->create(entry.params, context));
    robot.sensor_names.push_back(entry.kind->name);
  }
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
  robot.drive_model->Reset(d);
  for (auto& sensor : robot.sensors) sensor->OnPlaced({x_m, y_m, yaw_rad}, z);
  mj_kinematics(model_.get(), d);
  rays_->MarkMoved();
}

// ---------------------------------------------------------------------------------------------
// Robots

double MujocoSim::time_s() const { return data_->time; }
int64_t MujocoSim::utime() const { return ToUtime(data_->time); }
double MujocoSim::timestep_s() const { return model_->opt.timestep; }

SimStats MujocoSim::stats() const {
  SimStats stats = stats_;
  stats.rays_cast = rays_->rays_cast();
  stats.ray_s = rays_->ray_s();
  return stats;
}

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

const SimSensor* MujocoSim::sensor(const std::string& robot, const std::string& name) const {
  const Robot& r = FindRobot(robot);
  for (size_t i = 0; i < r.sensors.size(); ++i) {
    if (r.sensor_names[i] == name) return r.sensors[i].get();
  }
  return nullptr;
}

Status MujocoSim::TriggerSensor(const std::string& robot, const std::string& sensor) {
  if (!HasRobot(robot)) return common::NotFoundError("no robot '" + robot + "'");
  Robot& r = FindRobot(robot);
  for (size_t i = 0; i < r.sensors.size(); ++i) {
    if (r.sensor_names[i] != sensor) continue;
    const Status status = r.sensors[i]->Trigger(data_->time);
    if (status.ok()) return status;
    return Status(status.code(),
                  "robot '" + robot + "', sensor '" + sensor + "': " + status.message());
  }
  return common::NotFoundError("robot '" + robot + "' has no sensor '" + sensor + "'");
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
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  ApplyDrive(d->time, dt, out);
  const double time_before = d->time;
  saved_qpos_.assign(d->qpos, d->qpos + m->nq);
  saved_act_.assign(d->act, d->act + m->na);
  saved_mocap_pos_.assign(d->mocap_pos, d->mocap_pos + 3 * m->nmocap);
  saved_mocap_quat_.assign(d->mocap_quat, d->mocap_quat + 4 * m->nmocap);
  mj_step(model_.get(), data_.get());
  ++stats_.physics_steps;
  // Full contact or constraint buffers drop contacts silently: said once per run.
  for (int w : {mjWARN_CONTACTFULL, mjWARN_CNSTRFULL}) {
    if (d->warning[w].number > 0 && !buffer_full_reported_[w == mjWARN_CNSTRFULL]) {
      buffer_full_reported_[w == mjWARN_CNSTRFULL] = true;
      CAIRN_LOG_WARN("MuJoCo's %s buffer is full (%d needed): contacts are dropped",
                     w == mjWARN_CONTACTFULL ? "contact" : "constraint", d->warning[w].lastinfo);
    }
  }
  // MuJoCo resets mjData after a bad acceleration (its warning counters too, then counts this
  // one): a count above 0, or a clock that did not advance, is such a step.
  if (d->warning[mjWARN_BADQACC].number > 0 || !(d->time > time_before)) {
    UndoBadStep(time_before, dt, out);
  }
  AfterPhysicsStep(dt);
  const auto t1 = Clock::now();
  stats_.physics_s += Seconds(t0, t1);
  rays_->MarkMoved();
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
    r->drive_model->Apply(*r->drive, d, dt_s);
  }
}

void MujocoSim::UndoBadStep(double time_before_s, double dt_s, SimOutputs* out) {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  const int dof = d->warning[mjWARN_BADQACC].lastinfo;
  std::string who = "the world";
  for (const auto& r : robots_) {
    if (dof >= r->qvel_adr && dof < r->qvel_adr + 6) who = "robot '" + r->spec.id + "'";
  }
  d->warning[mjWARN_BADQACC].number = 0;
  ++stats_.unstable_steps;
  std::copy(saved_qpos_.begin(), saved_qpos_.end(), d->qpos);
  std::copy(saved_act_.begin(), saved_act_.end(), d->act);
  std::copy(saved_mocap_pos_.begin(), saved_mocap_pos_.end(), d->mocap_pos);
  std::copy(saved_mocap_quat_.begin(), saved_mocap_quat_.end(), d->mocap_quat);
  mju_zero(d->qvel, m->nv);
  mju_zero(d->qacc_warmstart, m->nv);
  d->time = time_before_s + dt_s;
  mj_forward(m, d);
  // One line a second of sim time at most: a robot left inside geometry fails every step.
  ++unstable_unlogged_;
  if (d->time - last_unstable_log_s_ >= 1.0) {
    char line[256];
    std::snprintf(line, sizeof(line),
                  "physics unstable at %.3f s (bad acceleration of dof %d, %s; %lld step%s since "
                  "the last report): the step is undone and everything stopped",
                  d->time, dof, who.c_str(), static_cast<long long>(unstable_unlogged_),
                  unstable_unlogged_ == 1 ? "" : "s");
    out->events.push_back(line);
    last_unstable_log_s_ = d->time;
    unstable_unlogged_ = 0;
  }
}

void MujocoSim::AfterPhysicsStep(double dt_s) {
  // The wheels' rotation over the step, for sensors that integrate it (odometry).
  for (auto& r : robots_) {
    const StepMotion motion = r->drive_model->Measure(data_.get(), dt_s);
    for (auto& sensor : r->sensors) sensor->OnStep(motion);
  }
}

void MujocoSim::ProduceReadings(SimOutputs* out) {
  const double now = data_->time;
  // Which sensors fall due at this step. Ray sensors need the poses of everything at `now`
  // (mj_step leaves the positions of the step's start in x*); the others read qpos, qvel and
  // sensordata directly.
  bool any_due = false, rays_due = false;
  for (const auto& r : robots_) {
    for (const auto& sensor : r->sensors) {
      if (!sensor->Due(now)) continue;
      any_due = true;
      rays_due |= sensor->CastsRays();
    }
  }
  if (!any_due) return;
  if (rays_due) mj_kinematics(model_.get(), data_.get());

  SensorFrame frame;
  frame.model = model_.get();
  frame.data = data_.get();
  frame.now_s = now;
  frame.utime = ToUtime(now);
  frame.rays = rays_.get();
  for (auto& r : robots_) {
    frame.robot_index = r->index;
    for (auto& sensor : r->sensors) {
      if (sensor->Due(now)) sensor->Produce(frame, out);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Objects and doors

void MujocoSim::SetGeomEnabled(int geom, bool enabled) {
  mjModel* m = model_.get();
  m->geom_contype[geom] = enabled ? 1 : 0;
  m->geom_conaffinity[geom] = enabled ? 1 : 0;
  m->geom_group[geom] = enabled ? 0 : kParkedGeomGroup;
  rays_->scene().SetVisible(geom, enabled);
  rays_->MarkMoved();
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
  rays_->MarkMoved();
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
  rays_->MarkMoved();
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
