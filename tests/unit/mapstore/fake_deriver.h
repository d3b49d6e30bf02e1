#pragma once

#include <cmath>
#include <limits>
#include <string>

#include "common/grid_map.h"
#include "common/layers.h"
#include "mapstore/map_store.h"
#include "tests/support/layers.h"

// Test doubles for the map store unit tests: a deterministic fake derivation and sample maps.

namespace cairn::mapstore::testing {

/// Fake derivation: a cell is lethal (100) when the elevation step to its +x neighbour exceeds
/// the profile's max_step_up_m, free (0) otherwise, NaN where the elevation is unknown (the
/// directed layer beside it: 255 where lethal, no one-way cells). An
/// obstacle is crossable when its slope and height are within the profile's limits.
inline ProfileDeriver FakeDeriver(const std::string& code_version = "fake-1") {
  ProfileDeriver d;
  d.code_version = code_version;
  d.derive = [](const common::GridMap& base, const common::RobotProfile& profile) {
    if (!base.HasLayer(layers::kElevation)) throw std::invalid_argument("no elevation layer");
    ProfileDeriver::Output out;
    out.layers = common::GridMap(base.geometry());
    const common::Layer& e = base.at(layers::kElevation);
    common::Layer& cost = out.layers.AddLayer(layers::CostLayer(profile.name));
    common::Layer& step = out.layers.AddLayer(layers::kStepMax);
    // The directed layer's contract (common/layers.h): NaN where the cost is, 255 where lethal.
    common::Layer& directed = out.layers.AddLayer(layers::DirectedLayer(profile.name));
    for (int iy = 0; iy < base.size_y(); ++iy) {
      for (int ix = 0; ix < base.size_x(); ++ix) {
        if (std::isnan(e(ix, iy))) continue;
        const int nx = std::min(ix + 1, base.size_x() - 1);
        const float d = std::isnan(e(nx, iy)) ? 0.f : std::abs(e(nx, iy) - e(ix, iy));
        step(ix, iy) = d;
        cost(ix, iy) = d > profile.max_step_up_m ? 100.f : 0.f;
        directed(ix, iy) = cost(ix, iy) >= 100.f ? layers::kAllHeadingsBlocked : 0.f;
      }
    }
    return out;
  };
  d.judge = [](const common::Obstacle& o, const common::RobotProfile& profile) {
    common::ObstacleVerdict v;
    v.profile = profile.name;
    v.profile_hash = profile.ContentHash();
    v.crossable = o.slope_rad <= profile.max_slope_up_rad && o.height_m <= profile.max_step_up_m;
    if (!v.crossable) v.reason = "too steep or too high";
    return v;
  };
  return d;
}

inline common::RobotProfile Profile(const std::string& name, double max_slope_deg,
                                    double max_step_m) {
  common::RobotProfile p;
  p.name = name;
  p.footprint_m = common::RectangleFootprint(0.6, 0.5);
  p.max_slope_up_rad = max_slope_deg * M_PI / 180.0;
  p.max_step_up_m = max_step_m;
  p.sensors = {"hdl32e"};
  return p;
}

using cairn::testing::SameLayer;

/// A map with a known pattern: elevation rises 0.05 m per cell in x from column 10 on (a
/// "ramp"), NaN in one corner; a second layer "observation_count".
inline MapSnapshot SampleSnapshot(const std::string& name, int size_x = 37, int size_y = 23,
                                  float offset = 0.f) {
  MapSnapshot s;
  s.site = "lab";
  s.name = name;
  s.provenance.source_robot = "rover1";
  s.provenance.source_profile = "pioneer3at";
  s.provenance.source_profile_hash = "abc123";
  s.provenance.code_version = "mapping-7";
  s.provenance.parameters = "resolution_m: 0.2\n";
  s.provenance.created_utime = 1700000000000000 + static_cast<int64_t>(offset * 1000);
  common::GridGeometry g;
  g.resolution_m = 0.2;
  g.size_x = size_x;
  g.size_y = size_y;
  g.origin = {-1.5, 2.25, 0.3};
  s.base = common::GridMap(g);
  common::Layer& e = s.base.AddLayer(layers::kElevation);
  common::Layer& c = s.base.AddLayer(layers::kObservationCount);
  for (int iy = 0; iy < size_y; ++iy) {
    for (int ix = 0; ix < size_x; ++ix) {
      e(ix, iy) = offset + (ix >= 10 ? 0.05f * (ix - 10) : 0.f) + 0.001f * iy;
      c(ix, iy) = static_cast<float>(ix * 1000 + iy);
    }
  }
  for (int iy = 0; iy < 3 && iy < size_y; ++iy) {
    for (int ix = 0; ix < 4 && ix < size_x; ++ix) e(ix, iy) = common::kUnknown;
  }
  common::Obstacle ramp;
  ramp.id = 7;
  ramp.kind = common::ObstacleKind::kRamp;
  ramp.centroid_m = {1.0, 3.0};
  ramp.outline_m = {{0.5, 2.5}, {1.5, 2.5}, {1.5, 3.5}, {0.5, 3.5}};
  ramp.slope_rad = 10.0 * M_PI / 180.0;
  ramp.height_m = 0.02;
  ramp.width_m = 1.0;
  ramp.length_m = 1.0;
  ramp.depth_m = std::numeric_limits<double>::quiet_NaN();
  ramp.area_m2 = 1.0;
  ramp.num_cells = 25;
  ramp.verdicts.push_back({"pioneer3at", "abc123", false, "slope 10.0 deg > 8.0 deg"});
  common::Obstacle step;
  step.id = 3;
  step.kind = common::ObstacleKind::kStepUp;
  step.centroid_m = {2.0, 4.0};
  step.outline_m = {{1.9, 3.5}, {2.1, 3.5}, {2.1, 4.5}};
  step.height_m = 0.2;
  step.width_m = 0.2;
  step.length_m = 1.0;
  step.depth_m = 0.0;
  step.area_m2 = 0.2;
  step.num_cells = 5;
  s.obstacles.obstacles = {ramp, step};
  return s;
}

/// A cache entry for profile "rover" (hash "h1", code version "c1") on `geometry`, with a
/// cost layer of zeros and no obstacles: tests fill in what they check.
inline DerivedProfile RoverDerivation(const common::GridGeometry& geometry) {
  DerivedProfile d;
  d.profile_name = "rover";
  d.profile_hash = "h1";
  d.code_version = "c1";
  d.layers = common::GridMap(geometry);
  d.layers.AddLayer("cost/rover", 0.f);
  return d;
}

}  // namespace cairn::mapstore::testing
