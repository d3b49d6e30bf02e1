#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "services/explore/info_map.h"
#include "services/explore/interest_zone.h"

/// @file
/// Next-best-view (seed 002 §4.2–4.3): random candidates on safe cells, the navigation tree from
/// the robot's cell, and for each reachable candidate c
///
///   u(c) = (w_A A(c) + w_Q Q(c) + w_O O(c)) / (w_C C(c))
///
/// with A the unexplored area it would see (2-D ray casting, occluded by cells whose C_nc is
/// below occlusion_cnc or where a wall spans the scanner's height), Q the quality it would
/// add, O the occluded planes it would face and C the path cost. Exploration stops when the best u
/// falls below C_p = 0.5 / (w_C d_max) once the mean quality has reached its minimum, or when no
/// candidate is reachable. The greedy baseline (Koenig, Tovey and Halliburton) goes wherever A is
/// largest.

namespace cairn::explore {

struct NbvWeights {
  double w_a{0.43};  ///< information gain
  double w_q{0.35};  ///< quality gain
  double w_o{0.22};  ///< interest zones
  double w_c{0.09};  ///< path cost, 1/m
};

enum class NbvStrategy { kUtility, kGreedy };

struct NbvParams {
  NbvStrategy strategy{NbvStrategy::kUtility};
  NbvWeights weights;
  double d_max_m{50.0};                ///< stop rule: C_p = 0.5 / (w_C d_max)
  double min_global_quality{0.0};      ///< do not stop below this mean Q_a
  double safe_cnc{0.7};                ///< candidates and path cells need C_nc above it
  double candidate_spacing_m{3.0};     ///< candidates lie further apart (and from the robot)
  int candidate_fraction{50};          ///< at most 1 / candidate_fraction of the safe cells
  double candidate_clearance_m{0.45};  ///< every cell this near a candidate must be safe too
  /// No candidate this near a view point already scanned: the same view gives the same points,
  /// nothing new, whatever the gains' model expects of it (0: no such rule).
  double revisit_radius_m{1.5};
  /// Unexplored cells this near the robot count as safe for the navigation tree: the scanner's
  /// blind cone below it (a 270 deg fan 1 m up leaves about 1 m unseen around the robot).
  double robot_free_radius_m{1.5};
  /// Cells below it block the view (so do cells where a wall spans the scanner's height).
  double occlusion_cnc{0.4};
  double gain_range_m{20.0};     ///< useful scanner radius for A, Q and O
  double scanner_height_m{1.0};  ///< above the ground, for Q's distances
  double pan_step_rad{0.5 * 3.14159265358979323846 / 180.0};
  double tilt_step_rad{0.5 * 3.14159265358979323846 / 180.0};
  double a_max_m2{0.0025};
  double w_a_quality{0.93};      ///< the quality combination's area weight
  double w_n_quality{0.07};      ///< and incidence weight
  double greedy_min_gain{0.02};  ///< the greedy baseline stops below this A
  /// An unexplored cell that k scans from one direction (an octant) should have seen (by the
  /// 2-D model A uses) and did not, the nearest from d metres, weighs 2^-k in A for a view from
  /// that direction, or 1 again for a view nearer than d - missed_view_step_m or from another
  /// direction: the inside of a building, ground behind a crest or between the far rings of a
  /// scan. A nearer view sees the ground steeper and over more crests, a view from elsewhere
  /// round the house; a view from about as far the same way would likely miss it again.
  double missed_view_step_m{3.0};
  uint64_t seed{1};

  /// @throws std::invalid_argument naming the bad field.
  void Validate() const;
};

/// A named preset of seed 002's tables 6-2, 6-4, 6-6, 6-8 and 6-9 (for example
/// "simple-balanced", or "greedy" for the baseline), applied over `base`.
/// @throws std::invalid_argument listing the known names for an unknown one.
NbvParams NbvPreset(const std::string& name, NbvParams base = {});
std::vector<std::string> NbvPresetNames();

/// u(c) (eq. 2.3). A zero cost is floored at 1e-9.
double Utility(const NbvWeights& w, double info_gain, double quality_gain, double zone_gain,
               double path_cost);
/// C_p (eq. 4.12).
double StopThreshold(double w_c, double d_max_m);
/// D(p)'s combination of an area and an incidence score (eq. 3.27).
double CombineQuality(double area_score, double incidence_score, double w_a, double w_n);

/// Least-cost tree over the info map's nodes from one node: 4-neighbour steps cost
/// cell_size / C_nc(child) and may only enter nodes with C_nc > safe_cnc (the root may be
/// anything). Dijkstra; the same costs as the thesis's wavefront with re-parenting. A step into a
/// cell of two levels enters the level whose ground is nearest the ground it leaves: over a
/// bridge's deck from its ramps, under it from the road.
struct NavigationTree {
  int64_t root{-1};
  std::vector<float> cost;      ///< per node; +inf where unreachable
  std::vector<int64_t> parent;  ///< -1 at the root and where unreachable
  bool Reachable(int64_t node) const { return std::isfinite(cost[node]); }
  /// Nodes from the root to `node` (empty when unreachable).
  std::vector<int64_t> PathTo(int64_t node) const;
};
/// Unexplored cells within free_radius_m of the root count as safe (C_nc 1) on the lower level:
/// the robot stands there, and a scanner on it does not see the ground in its blind cone below.
/// `root_ground_z_m`: the robot's ground where the root has none of its own (NaN: unknown).
NavigationTree BuildNavigationTree(const InfoMap& map, int64_t root, double safe_cnc,
                                   double free_radius_m = 0.0,
                                   float root_ground_z_m = std::numeric_limits<float>::quiet_NaN());

struct Candidate {
  int64_t cell{-1};  ///< the view's node (InfoMap: cell + level * cells)
  common::Vector2 position_m{0.0, 0.0};
  double info_gain{0.0};     ///< A in [0, 1]
  double quality_gain{0.0};  ///< Q in [0, 1]
  double zone_gain{0.0};     ///< O in [0, 1]
  double path_cost{0.0};     ///< C, metres over C_nc
  double utility{0.0};       ///< u (greedy: A)
  bool reachable{false};
  /// The chosen candidate's path through the navigation tree (cell centres from the robot's
  /// cell) and its length; empty and 0 for the others.
  std::vector<common::Vector2> path_m;
  std::vector<int64_t> path_nodes;  ///< the same path as info-map nodes (cell and level)
  double path_length_m{0.0};
  double ground_z_m{0.0};  ///< the chosen candidate's ground (InfoMap::GroundHeight)
};

/// Safe nodes at random, pairwise further apart than the spacing, at most 1/candidate_fraction
/// of the safe cells, inside the work area, with a safe clearance, and not within the spacing
/// of the robot or within revisit_radius_m of a view point in `visited`. The draw is stable: every
/// cell has a fixed random rank (a hash of its index and `seed`) and the candidates are taken in
/// rank order, so a cell that stays safe keeps its chances from one decision to the next and a
/// small change of the map (another scan's noise) changes the sample only where it changed the safe
/// cells, not everywhere.
std::vector<int64_t> SampleCandidates(const InfoMap& map, const NbvParams& params,
                                      const common::Vector2& robot_m, uint64_t seed,
                                      const std::vector<common::Vector2>& visited = {});
/// The rank of `cell` under `seed` (SplitMix64 of both).
uint64_t CandidateRank(int64_t cell, uint64_t seed);

/// The gains of a view from `cell` (scanner at scanner_height_m above the cell's ground).
struct ViewGains {
  double info_gain{0.0};
  double quality_gain{0.0};
  double zone_gain{0.0};
  std::vector<size_t> zones_seen;  ///< indices into the zone list
  /// The unexplored work-area cells the view should see (only when asked for).
  std::vector<int64_t> unexplored;
};

/// Per cell and per direction, the scans that should have seen it and did not: how many, and the
/// distance (m) of the nearest (+inf when none). NbvParams::missed_view_step_m. The direction is
/// the octant (45 degrees) of the bearing from the cell to the scan: what hid a cell from the
/// south-west (a house, a crest) need not hide it from the north.
struct MissedViews {
  static constexpr int kSectors = 8;
  explicit MissedViews(int64_t num_cells);
  /// The octant of the bearing (dx, dy), in cells, from a cell to a view: 0 is east, counted
  /// anticlockwise.
  static int Sector(int64_t dx, int64_t dy);
  int64_t num_cells() const { return static_cast<int64_t>(count.size()) / kSectors; }
  std::vector<float> nearest_m;  ///< [cell * kSectors + sector]
  std::vector<uint8_t> count;    ///< [cell * kSectors + sector]
  /// The cell's weight in A for a view d_m away in direction `sector`.
  double Weight(int64_t cell, int sector, double d_m, double step_m) const;
};
/// Records a scan from `cell` that did not see the cells of `unexplored`.
/// @returns how many cells were missed for the first time (from any direction).
int64_t RecordMissedView(const InfoMap& map, int64_t cell, const std::vector<int64_t>& unexplored,
                         MissedViews* missed);
class ViewEvaluator {
 public:
  /// `missed` (one entry per map cell, or null) removes the cells given up on from A.
  ViewEvaluator(const InfoMap& map, const NbvParams& params, const MissedViews* missed = nullptr);
  ViewGains Evaluate(int64_t cell, const std::vector<InterestZone>& zones,
                     bool list_unexplored = false);

 private:
  const InfoMap& map_;
  NbvParams params_;
  const MissedViews* missed_;
  std::vector<uint32_t> stamp_;
  uint32_t epoch_{0};
  std::vector<int64_t> visible_;
};

struct NbvDecision {
  enum class Outcome { kGoTo, kStopUtility, kNoCandidate };
  Outcome outcome{Outcome::kNoCandidate};
  std::optional<Candidate> best;
  std::vector<Candidate> candidates;  ///< every sampled candidate, scored
  double stop_threshold{0.0};         ///< C_p
  double global_quality{0.0};
  double coverage{0.0};
  std::string reason;  ///< one line: why this outcome
};

class NbvPlanner {
 public:
  explicit NbvPlanner(const NbvParams& params);
  /// One decision from the robot's position (which must lie on the map).
  /// @throws std::invalid_argument when the robot is off the map.
  /// `missed` (or null) as ViewEvaluator's; `visited`: the view points scanned so far;
  /// `robot_ground_z_m` picks the level the robot stands on (NaN: the lower one).
  NbvDecision Decide(const InfoMap& map, const std::vector<InterestZone>& zones,
                     const common::Vector2& robot_m, const MissedViews* missed = nullptr,
                     const std::vector<common::Vector2>& visited = {},
                     float robot_ground_z_m = std::numeric_limits<float>::quiet_NaN());
  const NbvParams& params() const { return params_; }

 private:
  NbvParams params_;
};

const char* OutcomeName(NbvDecision::Outcome outcome);

}  // namespace cairn::explore
