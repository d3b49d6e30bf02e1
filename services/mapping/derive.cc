#include "services/mapping/derive.h"

#include "common/check.h"
#include "common/layers.h"
#include "services/mapping/sonar_derive.h"
#include "services/mapping/sonar_mapper_layer.h"

namespace cairn::mapping {

// Bump whenever a change to traversability.cc or obstacles.cc could change a derived value.
const char kMappingCodeVersion[] = "cairn-terrain-4";

DerivedLayers DeriveProfileLayers(const common::GridMap& base, const common::RobotProfile& profile,
                                  const TraversabilityParams& traversability,
                                  const ObstacleParams& obstacles) {
  // A sonar map (no elevation: the sonar scans a plane at the vehicle's depth).
  if (!base.HasLayer(layers::kElevation) && base.HasLayer(kSonarOccupancy)) {
    return DeriveSonarProfileLayers(base, profile);
  }
  CAIRN_THROW_UNLESS(
      base.HasLayer(layers::kElevation),
      "cannot derive profile layers: the map has neither an '"
          << layers::kElevation << "' nor a '" << kSonarOccupancy << "' layer");
  profile.Validate();
  // Work on a copy holding only what derivation reads, so the base map is never touched.
  common::GridMap work(base.geometry());
  work.AddLayer(layers::kElevation) = base.at(layers::kElevation);
  for (const char* name : {layers::kGroundBound, layers::kElevationVariance}) {
    if (base.HasLayer(name)) work.AddLayer(name) = base.at(name);
  }
  ComputeGeometricLayers(&work, traversability);
  ComputeCostLayer(&work, profile, traversability);

  DerivedLayers out;
  out.registry = ExtractObstacles(work, obstacles);
  LabelObstacles(&out.registry, {profile});
  out.layers = common::GridMap(base.geometry());
  for (const std::string& name :
       {std::string(layers::kSlope), std::string(layers::kStepMax), std::string(layers::kRoughness),
        std::string(layers::kDitchDepth), std::string(layers::kDitchWidth),
        layers::CostLayer(profile.name), layers::DirectedLayer(profile.name)}) {
    out.layers.AddLayer(name) = work.at(name);
  }
  return out;
}

}  // namespace cairn::mapping
