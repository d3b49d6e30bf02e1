#pragma once

#include <ompl/base/spaces/DubinsStateSpace.h>

/// @file
/// DubinsSpace: OMPL's Dubins state space with its path computation redone without internal
/// assertions. OMPL 1.5.2 (Debian) snaps angles within 5e-7 rad of 2π to 0 and then asserts a
/// geometric identity to 2e-6 in units of the turning radius, which fails, aborting the process,
/// for motions longer than a few turning radii that start tangent to their straight segment:
/// exactly the states a tree planner makes by interpolating along Dubins curves. The words
/// (LSL, RSR, RSL, LSR, RLR, LRL; Shkel and Lumelsky, "Classification of the Dubins set", 2001)
/// and the curve interpolation are OMPL's own; only the assertions are gone.

namespace cairn::planner {

class DubinsSpace : public ompl::base::DubinsStateSpace {
 public:
  /// @param turning_radius_m minimum turning radius, > 0.
  explicit DubinsSpace(double turning_radius_m)
      : ompl::base::DubinsStateSpace(turning_radius_m, false) {}

  /// Length of the shortest Dubins path, in metres.
  double distance(const ompl::base::State* a, const ompl::base::State* b) const override;
  void interpolate(const ompl::base::State* from, const ompl::base::State* to, double t,
                   ompl::base::State* state) const override;
  void interpolate(const ompl::base::State* from, const ompl::base::State* to, double t,
                   bool& first_time, DubinsPath& path, ompl::base::State* state) const override;

  /// The shortest Dubins path from a to b (lengths in units of the turning radius).
  DubinsPath ShortestPath(const ompl::base::State* a, const ompl::base::State* b) const;
};

}  // namespace cairn::planner
