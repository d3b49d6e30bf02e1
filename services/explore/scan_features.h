#pragma once

#include <vector>

#include "services/explore/interest_zone.h"
#include "services/explore/scan_mesh.h"
#include <Eigen/Core>

/// @file
/// Per-scan 3-D analysis of seed 002 (§3.4-3.6): per point a navigability F(p), an obstacle
/// score B(p) and a model quality D(p), and the occluded interest zones of the scan.
///
/// A point is valid when it has a return and a normal (it lies in an accepted mesh triangle);
/// every score of an invalid point is NaN. Symbols, per valid point p:
/// - N(p): the mesh normal (unit, towards the sensor); r̂: unit ray from the scanner centre to p;
/// - P_z(p) = p.z - robot_base_z_m; d_xy(p): horizontal distance from the scanner centre to p
///   (the robot base is under the scanner centre);
/// - θ = max_slope_rad, the robot's climbing angle.
///
/// Considered zone (seed Fig. 3-4): p is reachable when P_z <= d_xy tan θ, i.e. it lies on or
/// below the cone of slope θ whose apex is the robot base: reaching it needs no climb steeper
/// than θ. Points above the cone get F = 0 (and count as 0 in their neighbours' F_pg).
///
/// Navigability (eqs. 3.14-3.18): F_pl = S · H for reachable points, F_pg = mean F_pl over the
/// mesh neighbours, F = clamp(w_l F_pl + w_g F_pg, 0, 1).
///
/// Obstacles (eqs. 3.19-3.21). Each valid point gets a local ground height g(p): the lowest
/// ground point (a reachable point whose slope term S >= 0.5, i.e. a slope up to θ) in the
/// 3 x 3 horizontal cells of ground_cell_m around p, or the robot base where there is none. p is
/// in the obstacle band when 0 <= p.z - g(p) <= obstacle_band_m and its foot is reachable
/// (g - robot base <= d_xy tan θ). Then, [R] the seed's recommended form,
///   B_l(p) = clamp(|N_xy| · H(g(p) - robot base, d_xy) · |r̂ · N|, 0, 1),
/// else B_l = 0. H is taken at the obstacle's foot, not at p: H says how reachable the position
/// is, while the point's own height is already bounded by the band (H at p would make a 0.8 m
/// box 3 m away score about 0.7 instead of the seed's > 0.83). B_g = mean B_l over the mesh
/// neighbours, B = clamp(w_bl B_l + w_bg B_g, 0, 1) in the band, 0 outside it.
///
/// Quality (eqs. 3.23-3.27): D_A = AreaQuality(PAR, a_max_m2), D_I = |r̂ · N|,
/// D = CombinedQuality(D_A, D_I, w_a, w_n).
///
/// Interest zones (§3.6, InterestZone in services/explore/interest_zone.h): the rejected
/// triangles grouped by shared edges (union-find); each group whose area (the sum of its
/// triangles' areas) exceeds min_zone_area_m2 becomes a zone with
/// - center_m: the mean of the group's distinct vertices, p_co (eq. 3.28);
/// - normal: direction the area-weighted sum of the triangles' normals, each oriented towards
///   the sensor, normalised; magnitude the group's area, so |normal| = area_m2 (eq. 3.29, [R]:
///   the lost normaliser K is chosen so that |n_o| is the occluded area itself). It points to
///   the open side: a triangle spanning a depth jump joins the occluder's silhouette edge to the
///   background behind it, and the sensor lies on its side away from the occluder, so the normal
///   points away from the occluder (out of a box's left edge: left; its top edge: up).

namespace cairn::explore {

struct ScanAnalysisParams {
  /// θ, the robot's climbing angle, in (0, 90 deg). The thesis does not give the value it used
  /// (Appendix A); 20 deg is the robauco profile's.
  double max_slope_rad{20.0 * M_PI / 180.0};
  /// The robot's descent angle for H below its base (dz < 0), in (0, 90 deg); 0: θ, the seed's
  /// symmetric H. A robot that may descend steeper than it climbs (the rover: 20 deg down, 12
  /// up) sees a 7 deg ramp down ahead as navigable (H 0.71), which with θ it would not (0.56).
  double max_descent_rad{0.0};
  /// k in S(p), [R]: the seed's form lost this single glyph; 10 is its suggested default.
  double slope_steepness{10.0};
  double w_l{0.66};   ///< weight of the local navigability F_pl (Table 6-1)
  double w_g{0.33};   ///< weight of the neighbourhood navigability F_pg
  double w_bl{0.55};  ///< weight of the local obstacle score B_l
  double w_bg{0.45};  ///< weight of the neighbourhood obstacle score B_g
  /// Height of the obstacle band above the local ground: the robot's height with the scanner.
  double obstacle_band_m{1.0};
  /// Horizontal cell size of the local-ground search (3 x 3 cells around each point).
  double ground_cell_m{0.5};
  /// Points farther than this horizontally from the scanner centre find no local ground and use
  /// the robot base (bounds the ground grid; the LMS111 reaches 50 m).
  double ground_grid_radius_m{60.0};
  double a_max_m2{0.0025};  ///< A_max: desired maximum area per point (Table 6-1)
  double w_a{0.93};         ///< weight of the area score D_A in D
  double w_n{0.07};         ///< weight of the incidence score D_I in D
  /// Smallest area of an interest zone (sum of its rejected triangles' areas). The seed leaves
  /// it open; 0.5 m² drops the thin slivers along small steps and stones (a 0.3 m depth jump
  /// along a 1 m edge makes 0.3 m²) and keeps the shadow of anything a robot could hide behind.
  double min_zone_area_m2{0.5};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// Per-point scores, each with scan.size() entries, NaN for invalid points.
struct ScanFeatures {
  std::vector<float> navigability;  ///< F(p) in [0, 1]; 0 above the slope cone
  std::vector<float> obstacle;      ///< B(p) in [0, 1]; 0 outside the band or unreachable
  std::vector<float> quality;       ///< D(p) in [0, 1]
  /// Zones by decreasing area (ties: the group holding the earlier rejected triangle first).
  std::vector<InterestZone> zones;
};

/// Analyses one scan with its mesh (BuildScanMesh(scan, ...)).
/// @throws std::invalid_argument if the scan or params are invalid, or the mesh does not fit
/// the scan (sizes, vertex or neighbour indices, triangles that are not grid triangles).
ScanFeatures AnalyseScan(const OrderedScan& scan, const ScanMesh& mesh,
                         const ScanAnalysisParams& params);

/// S(p) = 1 / (1 + exp(-k (n_z - cos θ) / (1 - cos θ))) (eq. 3.15, [R]: k was lost): 0.5 at
/// n_z = cos θ, towards 1 for level ground, > 0 beyond θ.
/// @throws std::invalid_argument unless n_z is in [-1, 1], θ in (0, π/2) and k > 0.
double SlopeTerm(double n_z, double theta_rad, double k);

/// H(p) = exp(-|dz| / (d_xy tan θ)) (eq. 3.16, [R]): 1 at the robot's height, in (0, 1]. Below
/// the base with ScanAnalysisParams::max_descent_rad set, that angle stands in for θ.
/// d_xy is clamped to at least 1 mm (a point straight above or below the scanner).
/// @throws std::invalid_argument unless dz is finite, d_xy >= 0 and θ in (0, π/2).
double HeightTerm(double dz_m, double d_xy_m, double theta_rad);

/// D_A = 1 if par <= a_max, else a_max / par (eq. 3.23).
/// @throws std::invalid_argument unless par >= 0 and a_max > 0.
double AreaQuality(double par_m2, double a_max_m2);

/// D = sqrt((w_a d_a)² + (w_n d_i)²) / sqrt(w_a² + w_n²) (eq. 3.27), in [0, 1].
/// @throws std::invalid_argument unless d_a, d_i are in [0, 1], the weights >= 0 and not both 0.
double CombinedQuality(double d_a, double d_i, double w_a, double w_n);

}  // namespace cairn::explore
