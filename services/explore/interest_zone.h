#pragma once

#include <Eigen/Core>

/// @file
/// An interest zone (seed 002 §3.3.3): an occluded plane of the model, found from the triangles
/// the mesh rejected across a depth jump. Its normal points to the open side (towards the scanner
/// that saw its rim) and its length is the hole's area, so that a view facing a large hole scores
/// more. A zone leaves the list once a later scan has seen into it.

namespace cairn::explore {

struct InterestZone {
  Eigen::Vector3f center_m{0.f, 0.f, 0.f};  ///< mean of the rejected triangles' vertices (world)
  Eigen::Vector3f normal{0.f, 0.f, 0.f};    ///< |normal| = area_m2
  float area_m2{0.f};
};

}  // namespace cairn::explore
