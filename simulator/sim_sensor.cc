#include "simulator/sim_sensor.h"

#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>

namespace cairn::sim {

NoiseSource SensorContext::Noise() const {
  return NoiseSource(seed, NoiseStream(robot + "/" + sensor));
}

std::string SensorContext::Where() const { return "robot '" + robot + "' (" + model_path + "): "; }

int SensorContext::RequireSite(const std::string& site) const {
  const int id = mj_name2id(model, mjOBJ_SITE, (robot + "/" + site).c_str());
  if (id < 0) {
    throw std::invalid_argument(Where() + "sensor '" + sensor + "' needs a site named '" + site +
                                "' on the robot");
  }
  return id;
}

common::Pose3 SitePose(const mjData* data, int site) {
  common::Pose3 pose;
  pose.position_m = common::Vector3(data->site_xpos[3 * site], data->site_xpos[3 * site + 1],
                                    data->site_xpos[3 * site + 2]);
  const Eigen::Matrix3d rotation =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(data->site_xmat + 9 * site);
  pose.orientation = common::Quaternion(rotation).normalized();
  return pose;
}

int64_t ToUtime(double t_s) { return static_cast<int64_t>(std::llround(t_s * 1e6)); }

}  // namespace cairn::sim
