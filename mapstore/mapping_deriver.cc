#include "mapstore/mapping_deriver.h"

#include "services/mapping/derive.h"
#include "services/mapping/obstacles.h"

namespace cairn::mapstore {

ProfileDeriver MappingDeriver() {
  ProfileDeriver d;
  d.code_version = mapping::kMappingCodeVersion;
  d.derive = [](const common::GridMap& base, const common::RobotProfile& profile) {
    mapping::DerivedLayers derived = mapping::DeriveProfileLayers(base, profile);
    ProfileDeriver::Output out;
    out.layers = std::move(derived.layers);
    out.registry = std::move(derived.registry);
    return out;
  };
  d.judge = [](const common::Obstacle& obstacle, const common::RobotProfile& profile) {
    return mapping::JudgeObstacle(obstacle, profile);
  };
  d.judge_parts = [](const common::Obstacle& obstacle, const common::RobotProfile& profile) {
    return mapping::JudgeParts(obstacle, profile);
  };
  return d;
}

}  // namespace cairn::mapstore
