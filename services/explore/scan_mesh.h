#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

/// @file
/// Triangulation of one stop-and-scan 3-D scan on its ordered grid (seed 002 §3.1, §3.3).
///
/// The scan is a grid of num_lines pan lines x beams_per_line beams. Each grid quad (line l,
/// beam b) .. (l + 1, b + 1) gives
/// - two triangles split along the fixed diagonal (l, b)-(l + 1, b + 1) when its four corners
///   have returns (a fixed diagonal gives every interior point six triangles, so the area per
///   point of a regular grid is exactly one quad: PAR = r² · res_p · res_t at range r);
/// - one triangle of its three valid corners when one corner has no return;
/// - nothing otherwise. No triangle ever uses a cell without return, and there are at most
///   2 (num_lines - 1)(beams_per_line - 1) triangles.
/// The pan lines are not closed into a ring (the last line is not joined to the first).
///
/// Each triangle then passes the law-of-sines test (see MeshParams) or goes, unchanged, to the
/// rejected list, which later gives the occluded interest zones (services/explore/
/// scan_features.h). Accepted triangles give each point its area per point, its normal and its
/// mesh neighbours.

namespace cairn::explore {

/// One stop-and-scan 3-D scan as an ordered grid: num_lines pan lines x beams_per_line beams
/// (a rotating planar laser: each line is one vertical fan at one pan angle).
struct OrderedScan {
  int num_lines{0};
  int beams_per_line{0};
  /// World frame, z up, already rotated to the vertical; index line * beams_per_line + beam.
  /// A point with a NaN (or infinite) coordinate has no return.
  std::vector<Eigen::Vector3f> points_m;
  Eigen::Vector3f sensor_origin_m{0, 0, 0};  ///< scanner centre (world)
  float robot_base_z_m{0.f};                 ///< ground height under the robot (world z)
  double pan_step_rad{0.5 * M_PI / 180};     ///< angular resolution between lines, res_p
  double tilt_step_rad{0.5 * M_PI / 180};    ///< angular resolution between beams, res_t

  /// Number of grid cells, num_lines * beams_per_line.
  int size() const { return num_lines * beams_per_line; }

  /// @throws std::invalid_argument naming the bad field: negative sizes, points_m.size() !=
  /// num_lines * beams_per_line, a grid over 2^31 - 1 cells, steps not finite and positive,
  /// a non-finite sensor origin or robot base.
  void Validate() const;
};

/// Triangle rejection bounds (seed 002 §3.1 leaves γmin and γmax open; Appendix A).
struct MeshParams {
  /// Law of sines: in a triangle sin θi / sin θj = (side opposite θi) / (side opposite θj), so
  /// the seed's γ = sin θ1 / sin θ2 lies in [1 / γmax, γmax] for every pair of angles exactly
  /// when longest side / shortest side <= γmax. A triangle is rejected when that side ratio
  /// exceeds this bound (γmin = 1 / max_side_ratio).
  /// A triangle across a depth jump Δ at range r has sides Δ and about r · step, so 20 rejects
  /// jumps over about 0.17 r at 0.5 deg (1.1 m at 5 m, 3.5 m at 20 m). Flat ground seen from a
  /// scanner h metres high gives triangles with a side ratio of about d / h at distance d, so it
  /// is kept out to about 20 h (20 m for the thesis robot's 1 m scanner); farther ground is
  /// rejected like a jump (the seed's test cannot tell them apart).
  double max_side_ratio{20.0};
  /// Also rejected: a triangle whose longest side exceeds this many times the grid spacing at
  /// its nearest vertex (range x max(pan_step, tilt_step)). The side ratio misses triangles whose
  /// three vertices all lie on different surfaces (mixed pixels at silhouettes); on surfaces the
  /// two bounds agree, so this one is set wider. 0 turns it off.
  double max_edge_spacing_ratio{40.0};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// The triangulated scan. Point arrays have scan.size() entries.
struct ScanMesh {
  /// Accepted triangles, vertex indices into points_m, counter-clockwise in (line, beam) order.
  std::vector<Eigen::Vector3i> triangles;
  /// Triangles that failed the law-of-sines test, kept for the interest zones.
  std::vector<Eigen::Vector3i> rejected_triangles;
  /// PAR(p) = sum of A_T / 3 over the accepted triangles T holding p (m²); NaN for a point in
  /// no accepted triangle (no return, or only rejected triangles).
  std::vector<float> area_per_point_m2;
  /// Area-weighted mean of the normals of p's accepted triangles, each oriented towards the
  /// sensor, normalised to unit length; NaN where PAR is NaN (and, degenerate, where the
  /// oriented normals cancel).
  std::vector<Eigen::Vector3f> normals;
  /// Mesh neighbours (points sharing an accepted triangle with p), compressed rows: p's
  /// neighbours are neighbours[neighbour_offsets[p] .. neighbour_offsets[p + 1]), at most 8,
  /// in increasing index order. neighbour_offsets has scan.size() + 1 entries.
  std::vector<int32_t> neighbour_offsets;
  std::vector<int32_t> neighbours;
};

/// Triangulates `scan` on its grid and computes the per-point area, normal and neighbours.
/// @throws std::invalid_argument if the scan or the params are invalid.
ScanMesh BuildScanMesh(const OrderedScan& scan, const MeshParams& params = {});

/// As above, into `mesh`, whose arrays are refilled in place: a caller that keeps one ScanMesh
/// and rebuilds it scan after scan allocates nothing once the capacities have grown (fresh
/// pages are most of the cost of a 175,000-point mesh on a virtual machine).
/// @throws std::invalid_argument if the scan or the params are invalid or `mesh` is null.
void BuildScanMesh(const OrderedScan& scan, const MeshParams& params, ScanMesh* mesh);

}  // namespace cairn::explore
