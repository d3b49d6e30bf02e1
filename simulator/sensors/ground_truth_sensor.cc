#include "simulator/sensors/ground_truth_sensor.h"

#include <cmath>

#include "common/check.h"
#include "simulator/sensor_registry.h"

namespace cairn::sim {

void GroundTruthParams::Validate() const {
  CAIRN_THROW_UNLESS(FinitePositive(rate_hz), "ground_truth.rate_hz must be > 0");
}

GroundTruthParams LoadGroundTruthParams(common::YamlMap& map, const GroundTruthParams& defaults) {
  GroundTruthParams p = defaults;
  map.Get("rate_hz", &p.rate_hz);
  FinishSensorParams(map, p);
  return p;
}

GroundTruthSensor::GroundTruthSensor(const GroundTruthParams& params, const SensorContext& context)
    : robot_(context.robot), qpos_adr_(context.qpos_adr), qvel_adr_(context.qvel_adr) {
  schedule_.rate_hz = params.rate_hz;
}

void GroundTruthSensor::Produce(const SensorFrame& frame, SimOutputs* out) {
  schedule_.Advance(frame.now_s);
  const double* q = frame.data->qpos + qpos_adr_;
  const double* v = frame.data->qvel + qvel_adr_;
  const common::Quaternion base_q = common::Quaternion(q[3], q[4], q[5], q[6]).normalized();
  GroundTruthReading g;
  g.utime = frame.utime;
  g.robot = robot_;
  g.pose.position_m = common::Vector3(q[0], q[1], q[2]);
  g.pose.orientation = base_q;
  // Free joint: linear velocity in the world frame, angular in the body frame.
  g.linear_velocity_mps = common::Vector3(v[0], v[1], v[2]);
  g.angular_velocity_radps = base_q * common::Vector3(v[3], v[4], v[5]);
  out->Add(kName, std::move(g));
}

}  // namespace cairn::sim
