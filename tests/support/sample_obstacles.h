#pragma once

// Sample registry entries for unit tests of the registry's codecs and conversions.

#include "common/obstacle.h"

namespace cairn::testing {

// A terrace with a ramp and a face, each with verdicts.
inline common::Obstacle SampleTerrace() {
  common::Obstacle t;
  t.id = 7;
  t.kind = common::ObstacleKind::kTerrace;
  t.centroid_m = {10.25, 2.0};
  t.outline_m = {{8, 0}, {12.2, 0}, {12.2, 4}, {8, 4}};
  t.slope_rad = 0.0872;
  t.height_m = 0.08;
  t.num_cells = 420;
  t.verdicts = {
      {"pioneer3at", "abc", false,
       "part 2 (face): step up 0.080 m > 0.030 m; one-way: crossable heading 0 deg only"}};
  common::ObstaclePart ramp;
  ramp.kind = common::ObstacleKind::kRamp;
  ramp.centroid_m = {8.45, 2.0};
  ramp.outline_m = {{8, 0}, {8.9, 0}, {8.9, 4}};
  ramp.slope_rad = 0.0872;
  ramp.height_m = 0.08;
  ramp.num_cells = 80;
  ramp.heading_in_rad = 0.01;
  ramp.verdicts = {{"pioneer3at", "abc", true, ""}};
  common::ObstaclePart face = ramp;
  face.kind = common::ObstacleKind::kStepUp;
  face.centroid_m = {12.0, 2.0};
  face.slope_rad = 0.0;
  face.heading_in_rad = 3.14159;
  face.verdicts = {{"pioneer3at", "abc", false,
                    "step up 0.080 m > 0.030 m; one-way: off the platform only, heading 0 deg"}};
  t.parts = {ramp, face};
  return t;
}

}  // namespace cairn::testing
