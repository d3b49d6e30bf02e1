#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <octomap/OcTree.h>

#include "common/point_cloud.h"
#include "common/status.h"
#include "services/mapping/octomap_batch_insert.h"

/// @file
/// The 3-D OctoMap layer: an octomap::OcTree fed with lidar revolutions, published in
/// OctoMap's own binary (.bt) or full (.ot) stream form and exportable as files that
/// octovis and the octomap tools read.
///
/// Insertion gives the same tree as OcTree::insertPointCloud(points, origin, max_range_m) on
/// the same scan (same voxels, same single update per voxel and scan, occupied wins over free)
/// but is several times faster; see octomap_batch_insert.h for how.

namespace cairn::common {
class YamlMap;
}  // namespace cairn::common

namespace cairn::mapping {

struct OctomapLayerParams {
  double resolution_m{0.1};
  double prob_hit{0.7};
  double prob_miss{0.4};
  double clamp_min{0.12};  ///< probability
  double clamp_max{0.97};
  double occupancy_threshold{0.5};
  /// Points farther than this from their sensor only clear space up to it (OctoMap's
  /// maxrange). At most 2000 voxels (200 m at 0.1 m), which bounds the work per ray.
  double max_range_m{30.0};
  double min_range_m{0.0};  ///< closer points (the robot itself) are dropped
  /// Collapse nodes whose eight children are equal leaves after each scan (as OctoMap's
  /// non-lazy insertion does); keeps the tree and its streams small.
  bool prune{true};

  /// @throws std::invalid_argument naming the first bad field.
  void Validate() const;
};

/// Reads the tree keys of an `octomap` section over the defaults. Does not call Finish: the
/// section also holds the mapper layer's keys. @throws common::ConfigError for a bad value.
OctomapLayerParams ReadOctomapLayerParams(common::YamlMap& map);

struct OctomapInsertStats {
  int64_t points{0};
  int64_t points_invalid{0};  ///< NaN or infinite coordinates, or a non-finite sensor pose
  int64_t points_too_close{0};
  int64_t rays_truncated{0};   ///< beyond max range: free space only
  int64_t rays_outside{0};     ///< outside the tree's addressable volume
  int64_t occupied_voxels{0};  ///< distinct voxels updated as occupied
  int64_t free_voxels{0};      ///< distinct voxels updated as free
  double voxels_s{0.0};        ///< time finding the voxels
  double tree_s{0.0};          ///< time updating the tree
};

/// The tree plus its insertion scratch. Movable, not copyable.
class OctomapLayer {
 public:
  /// @throws std::invalid_argument if the params are invalid.
  explicit OctomapLayer(const OctomapLayerParams& params = {});
  OctomapLayer(OctomapLayer&&) = default;
  OctomapLayer& operator=(OctomapLayer&&) = default;
  OctomapLayer(const OctomapLayer&) = delete;
  OctomapLayer& operator=(const OctomapLayer&) = delete;

  /// Inserts one scan of world points seen from `origin` (world metres).
  OctomapInsertStats InsertScan(const octomap::Pointcloud& points_world,
                                const octomap::point3d& origin);
  /// Inserts a revolution as one scan: each slice's points (sensor frame) are placed with
  /// that slice's sensor pose, and each ray starts at that slice's sensor position.
  OctomapInsertStats InsertRevolution(const common::LidarRevolution& revolution);

  const octomap::OcTree& tree() const { return *tree_; }
  octomap::OcTree& mutable_tree() { return *tree_; }
  const OctomapLayerParams& params() const { return params_; }
  /// Counts insertions and loads (for publishing only what changed).
  int64_t version() const { return version_; }

  /// The tree as a .bt stream (OctoMap's compact binary form: occupied / free per node, the
  /// maximum-likelihood map). The tree itself is not changed.
  std::string ToBinary() const;
  /// The tree as a .ot stream (full form, log-odds kept exactly).
  std::string ToFull() const;
  /// Writes the .bt or .ot form to a file.
  common::Status WriteBinaryFile(const std::string& path) const;
  common::Status WriteFullFile(const std::string& path) const;

  /// Replaces the tree with one read from a stream (.bt when `binary`, else .ot). The layer's
  /// sensor model is applied to the loaded tree. Fails with kCorrupt on a bad stream or a
  /// resolution different from the layer's, leaving the layer unchanged.
  common::Status Load(const std::string& bytes, bool binary);
  /// Forgets every voxel.
  void Clear();

 private:
  void ApplySensorModel(octomap::OcTree* tree) const;

  OctomapLayerParams params_;
  std::unique_ptr<octomap::OcTree> tree_;
  std::unique_ptr<internal::OctomapBatchInserter> inserter_;
  int64_t version_{0};
};

/// Reads a .bt (binary) or .ot (full) stream into a new OcTree. kCorrupt with a message when
/// the stream is not an OcTree.
common::Result<std::unique_ptr<octomap::OcTree>> ReadOcTree(const std::string& bytes, bool binary);

}  // namespace cairn::mapping
